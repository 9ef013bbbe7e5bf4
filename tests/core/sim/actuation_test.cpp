#include "sim/actuation.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"
#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

TEST(Actuation, NamesRoundTripAndAnUnknownNameIsRefusedNamingTheField) {
  for (Actuation a : kAllActuations) EXPECT_EQ(parse_actuation(actuation_name(a)), a);
  try {
    parse_actuation("teleport", "--actuation");
    FAIL() << "an unknown actuation was parsed";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(std::string(e.what()), "--actuation: expected one of mocap, arm, got \"teleport\"");
  }
}

TEST(Actuation, OnlyThePandaHasAnArmControllerAndFetchKeepsGymsMocap) {
  EXPECT_EQ(default_actuation(Robot::kFetch), Actuation::kMocap);
  EXPECT_NO_THROW(require_supported(Robot::kPanda, Actuation::kArm));
  EXPECT_NO_THROW(require_supported(Robot::kPanda, Actuation::kMocap));
  EXPECT_NO_THROW(require_supported(Robot::kFetch, Actuation::kMocap));
  try {
    require_supported(Robot::kFetch, Actuation::kArm, "actuation");
    FAIL() << "an arm-actuated Fetch was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("actuation: expected mocap for robot fetch"),
              std::string::npos)
        << e.what();
  }
}

// gym's 50 steps with the mocap hand; the arm, which covers less of each command, gets the
// arm's episode, the one the robot gateway plays (robot::GatewayConfig).
TEST(Actuation, TheArmsEpisodeIsLongerThanGyms) {
  EXPECT_EQ(episode_steps(Actuation::kMocap), 50);
  EXPECT_EQ(episode_steps(Actuation::kArm), layout::kArmEpisodeSteps);
  EXPECT_GT(episode_steps(Actuation::kArm), episode_steps(Actuation::kMocap));
}

}  // namespace
}  // namespace pnp::sim
