#include "sim/scripted_pipeline.h"

#include <gtest/gtest.h>

#include "common/rng.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_evaluation.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

// A small, fast version of the acceptance run (1000 episodes, in docs/SIMULATION.md).
TEST(ScriptedPipeline, PicksAndPlacesTheBlockOnBothRobotsInEveryWorld) {
  for (WorldProfile world : kAllWorldProfiles) {
    for (Robot robot : kAllRobots) {
      const ScriptedEvalReport r =
          evaluate_scripted(robot, ObjectShape::kBlock, 40, 2024, 0, world);
      EXPECT_EQ(r.world, world);
      EXPECT_GE(r.success_rate, 0.95) << world_profile_name(world) << " " << robot_name(robot);
      EXPECT_EQ(r.physics_faults, 0);
      EXPECT_EQ(r.env_steps, 40 * 50) << "every step counts, idle ones included";
      for (double s : r.subtask_success_rate) EXPECT_GE(s, 0.95) << world_profile_name(world);
    }
  }
}

TEST(ScriptedPipeline, SubtasksRunInOrderWithinTheirCaps) {
  PickPlaceEnv env(testing::world(Robot::kPanda, ObjectShape::kSmallBlock));
  const EpisodeOutcome out = run_scripted_episode(env, derive_seed(1, 0));
  EXPECT_TRUE(out.success);
  EXPECT_EQ(out.env_steps, 50);
  for (Subtask s : kAllSubtasks) {
    const auto k = static_cast<std::size_t>(s);
    EXPECT_TRUE(out.subtask_done[k]) << subtask_name(s);
    EXPECT_GT(out.subtask_steps[k], 0);
    EXPECT_LE(out.subtask_steps[k], step_cap(s, env.episode_steps()));
  }
  EXPECT_EQ(out.active_steps, out.subtask_steps[0] + out.subtask_steps[1] + out.subtask_steps[2]);
  EXPECT_LT(out.final_distance_m, 0.05);
}

TEST(ScriptedPipeline, FailsWhenTheGraspIsSabotaged) {
  // Negative control: with the object made immovable by a huge mass ratio... instead, we
  // remove the object from between the fingers mid-episode: the task must not succeed.
  PickPlaceEnv env(testing::world());
  env.reset(derive_seed(3, 0));
  // Step the approach, then teleport the object far away before the grasp.
  for (int t = 0; t < 3; ++t)
    env.step(Action{0, 0, 0, 1}, env.episode_goal(), Objective::kApproach);
  mjData* d = env.mj_data();
  d->qpos[env.world().ids().object_qpos + 0] = 1.10;
  d->qpos[env.world().ids().object_qpos + 1] = 0.45;
  while (!env.needs_reset()) env.step(Action{0, 0, 0, -1}, env.episode_goal(), Objective::kTask);
  EXPECT_FALSE(is_task_success(env.task_state().object, env.episode_goal()));
}

}  // namespace
}  // namespace pnp::sim
