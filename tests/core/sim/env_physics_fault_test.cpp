// A physics instability is detected, reported, and the world reset to a fresh episode
// rather than left broken.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "sim/pick_place_env.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

TEST(PhysicsFault, NonFiniteStateIsDetectedAndTheWorldReset) {
  PickPlaceEnv env(testing::world());
  env.reset(4);
  for (int t = 0; t < 5; ++t) env.step(Action{0.2, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach);
  // Corrupt the object's velocity, as a blown-up contact would.
  env.mj_data()->qvel[env.world().ids().object_dof] = std::numeric_limits<double>::quiet_NaN();
  const StepResult r = env.step(Action{0, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach);
  EXPECT_NE(r.fault, PhysicsFault::kNone);
  EXPECT_TRUE(r.episode_over);
  EXPECT_TRUE(r.observation.allFinite());
  EXPECT_EQ(env.elapsed_steps(), 0);
  EXPECT_FALSE(env.needs_reset());
  // The fresh episode steps normally.
  const StepResult next = env.step(Action{0, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach);
  EXPECT_EQ(next.fault, PhysicsFault::kNone);
  EXPECT_EQ(env.elapsed_steps(), 1);
}

TEST(PhysicsFault, HugeVelocityTriggersMuJoCosInstabilityWarning) {
  PickPlaceEnv env(testing::world(Robot::kPanda));
  env.reset(6);
  env.mj_data()->qvel[env.world().ids().object_dof + 2] = 1e12;
  const StepResult r = env.step(Action{0, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach);
  EXPECT_NE(r.fault, PhysicsFault::kNone);
  EXPECT_TRUE(r.observation.allFinite());
  EXPECT_LT((object_position(r.observation) - gripper_position(r.observation)).norm(), 0.5)
      << "the fresh episode puts the object back on the table";
}

// A contact blow-up can fling the object without any NaN or MuJoCo warning (seen: 3.6 m
// away at 200 rad/s). Impossible object motion is a fault too.
TEST(PhysicsFault, ObjectFlungAwayIsDetectedAndTheWorldReset) {
  PickPlaceEnv env(testing::world());
  env.reset(8);
  env.step(Action{0, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach);
  env.mj_data()->qvel[env.world().ids().object_dof] = 20.0;  // 20 m/s sideways: finite
  const StepResult r = env.step(Action{0, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach);
  EXPECT_EQ(r.fault, PhysicsFault::kEjected);
  EXPECT_TRUE(r.episode_over);
  EXPECT_EQ(env.elapsed_steps(), 0);
  EXPECT_LT((object_position(r.observation) - gripper_position(r.observation)).norm(), 0.5);
}

TEST(PhysicsFault, FastSpinIsAFault) {
  PickPlaceEnv env(testing::world(Robot::kPanda));
  env.reset(9);
  env.mj_data()->qvel[env.world().ids().object_dof + 5] = 300.0;  // rad/s about z
  EXPECT_EQ(env.step(Action{0, 0, 0, 1}, Goal{1, 1, 1}, Objective::kApproach).fault,
            PhysicsFault::kEjected);
}

TEST(PhysicsFault, NormalEpisodesReportNoFault) {
  PickPlaceEnv env(testing::world());
  env.reset(4);
  while (!env.needs_reset()) {
    ASSERT_EQ(env.step(Action{0.5, -0.5, -0.5, -1}, Goal{1, 1, 1}, Objective::kTask).fault,
              PhysicsFault::kNone);
  }
}

}  // namespace
}  // namespace pnp::sim
