#include "sim/observation.h"

#include <gtest/gtest.h>

#include <vector>

#include "sim/pick_place_env.h"
#include "sim/world_layout.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

TEST(Observation, LayoutAfterReset) {
  for (Robot robot : kAllRobots) {
    PickPlaceEnv env(testing::world(robot));
    const Observation o = env.reset(11);
    const mjData* d = env.mj_data();
    const WorldIds& ids = env.world().ids();
    for (int k = 0; k < 3; ++k) {
      EXPECT_DOUBLE_EQ(o(obs::kGripperPos + k), d->site_xpos[3 * ids.grip_site + k]);
      EXPECT_DOUBLE_EQ(o(obs::kObjectPos + k), d->xpos[3 * ids.object_body + k]);
      EXPECT_DOUBLE_EQ(o(obs::kObjectRelPos + k), o(obs::kObjectPos + k) - o(obs::kGripperPos + k));
    }
    EXPECT_LT((gripper_position(o) - layout::kGripperStart).norm(), 1e-3);
    EXPECT_NEAR(o(obs::kObjectPos + 2),
                layout::kTableTop_z + env.world().object_spec().half_height_m, 1e-9);
    EXPECT_DOUBLE_EQ(o(obs::kFingerPos), d->qpos[ids.finger_qpos[0]]);
    EXPECT_DOUBLE_EQ(o(obs::kFingerPos + 1), d->qpos[ids.finger_qpos[1]]);
    EXPECT_NEAR(finger_gap(o), 2 * env.world().finger_range_m(), 1e-3);  // open
    EXPECT_LT(o.segment<3>(obs::kObjectEuler).norm(), 1e-9);             // placed upright
    EXPECT_LT(o.segment<11>(obs::kObjectRelVel).norm(), 1e-3);           // at rest (14-24)
  }
}

TEST(Observation, VelocitiesAreTheStateAfterTheStepTimesTheStepDuration) {
  PickPlaceEnv env(testing::world());
  env.reset(3);
  const Goal goal = layout::kGripperStart;
  StepResult r;
  for (int t = 0; t < 3; ++t) r = env.step(Action{0.4, 0.2, -0.3, 1}, goal, Objective::kApproach);
  // Independent path: the grip site's Jacobian times the joint velocities.
  const mjModel* m = env.mj_model();
  const mjData* d = env.mj_data();
  std::vector<mjtNum> jacp(static_cast<std::size_t>(3 * m->nv));
  mj_jacSite(m, d, jacp.data(), nullptr, env.world().ids().grip_site);
  for (int k = 0; k < 3; ++k) {
    double v = 0;
    for (int j = 0; j < m->nv; ++j) v += jacp[static_cast<std::size_t>(k * m->nv + j)] * d->qvel[j];
    EXPECT_NEAR(r.observation(obs::kGripperVel + k), v * layout::kStepDuration_s, 1e-9);
  }
  EXPECT_GT(r.observation(obs::kGripperVel), 0.001);  // moving along +x
  // The object is still, so its velocity relative to the gripper is minus the gripper's.
  EXPECT_NEAR(r.observation(obs::kObjectRelVel), -r.observation(obs::kGripperVel), 1e-6);
  // Mean speed over a step is about the commanded 0.4 x 5 cm.
  const Eigen::Vector3d before = gripper_position(r.observation);
  r = env.step(Action{0.4, 0, 0, 1}, goal, Objective::kApproach);
  EXPECT_NEAR(gripper_position(r.observation).x() - before.x(), 0.4 * layout::kActionPositionScale,
              0.005);
}

TEST(Observation, FingerEntriesFollowTheGripperCommand) {
  PickPlaceEnv env(testing::world(Robot::kPanda));
  env.reset(4);
  const Goal goal = layout::kGripperStart;
  StepResult r;
  for (int t = 0; t < 3; ++t) r = env.step(Action{0, 0, 0, -1}, goal, Objective::kApproach);
  EXPECT_LT(finger_gap(r.observation), 0.005);  // closed on nothing
  for (int t = 0; t < 3; ++t) r = env.step(Action{0, 0, 0, 1}, goal, Objective::kApproach);
  EXPECT_NEAR(finger_gap(r.observation), 0.08, 0.002);  // Panda opens to 8 cm
}

}  // namespace
}  // namespace pnp::sim
