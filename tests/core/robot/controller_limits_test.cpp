#include "robot/controller_limits.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "robot/gateway_config.h"
#include "sim/panda_hand.h"

namespace pnp::robot {
namespace {

std::string refusal_for(const nlohmann::json& j) {
  try {
    ControllerLimits::from_json(j);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "accepted";
}

const std::filesystem::path kDeploy = std::filesystem::path(PNP_SOURCE_DIR) / "deploy" / "robot";

TEST(ControllerLimits, TheDeployedFileIsTheDefaultsAndHoldsTheGatewaysBox) {
  const ControllerLimits deployed = ControllerLimits::load(kDeploy / "controller.json");
  EXPECT_EQ(deployed.to_json(), ControllerLimits{}.to_json());
  // The controller's box contains the gateway's: the gateway refuses first.
  const robot::GatewayConfig gateway = robot::GatewayConfig::load(kDeploy / "gateway.json");
  EXPECT_TRUE(deployed.workspace.contains(gateway.limits.workspace.min_m));
  EXPECT_TRUE(deployed.workspace.contains(gateway.limits.workspace.max_m));
  EXPECT_GE(deployed.workspace.min_m.z(), sim::lowest_grip_point_z(deployed.table_top_z_m));
  EXPECT_LE(deployed.max_speed_m_per_s, 1.7);  // the Panda's Cartesian limit
}

TEST(ControllerLimits, EveryKeyIsCheckedAndNamed) {
  EXPECT_EQ(refusal_for({{"max_step", 0.1}}),
            "controller.max_step: unknown key (expected one of workspace, table_top_z_m, "
            "max_step_m, max_rotation_step_rad, max_speed_m_per_s, max_target_age_s)");
  EXPECT_EQ(refusal_for({{"max_speed_m_per_s", -1}}),
            "controller.max_speed_m_per_s: expected a positive finite number (m/s), got -1");
  EXPECT_NE(refusal_for({{"workspace", {{"min_m", {0.1, -0.4, 0.0}}}}})
                .find("controller.workspace.min_m[2]: expected at least 0.0121 m"),
            std::string::npos);
  EXPECT_NE(refusal_for({{"workspace", {{"max_m", {74, 0.4, 0.5}}}}})
                .find("controller.workspace.max_m[0]"),
            std::string::npos);
  EXPECT_EQ(refusal_for({{"max_rotation_step_rad", 0}}),
            "controller.max_rotation_step_rad: expected a positive finite number (rad), got 0");
  EXPECT_EQ(refusal_for({{"max_target_age_s", "soon"}}),
            "controller.max_target_age_s: expected a number, got \"soon\"");
}

TEST(ControllerLimits, RefusesOutsideTheBoxAndTooFarAStep) {
  const ControllerLimits l;
  const Eigen::Quaterniond down(0, 1, 0, 0);
  const geometry::Pose commanded{{0.45, 0.0, 0.2}, down};
  EXPECT_FALSE(l.refusal({{0.45, 0.0, 0.25}, down}, commanded));
  const auto below = l.refusal({{0.45, 0.0, 0.0}, down}, commanded);
  ASSERT_TRUE(below);
  EXPECT_NE(below->find("outside the controller's workspace"), std::string::npos) << *below;
  const auto far = l.refusal({{0.45, 0.3, 0.2}, down}, commanded);
  ASSERT_TRUE(far);
  EXPECT_NE(far->find("max_step_m"), std::string::npos) << *far;
  // The controller checks the turn itself, not only the gateway: 0.25 rad passes, 0.35 not.
  const auto turned = [&](double rad) {
    return geometry::Pose{
        {0.45, 0.0, 0.2},
        down * Eigen::Quaterniond(Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ()))};
  };
  EXPECT_FALSE(l.refusal(turned(0.25), commanded));
  const auto flipped = l.refusal(turned(0.35), commanded);
  ASSERT_TRUE(flipped);
  EXPECT_NE(flipped->find("max_rotation_step_rad 0.3"), std::string::npos) << *flipped;
  EXPECT_FALSE(l.refusal({{0.45, 0.0, 0.2}, Eigen::Quaterniond(3, 1, 0, 0)}, commanded))
      << "not a unit quaternion: the arm refuses it as an invalid target";
  EXPECT_DOUBLE_EQ(l.capped_speed(100, 1.0), 1.7);
  EXPECT_DOUBLE_EQ(l.capped_speed(0, 1.0), 1.0);  // 0: the arm's default
  EXPECT_DOUBLE_EQ(l.capped_speed(0.5, 1.0), 0.5);
}

}  // namespace
}  // namespace pnp::robot
