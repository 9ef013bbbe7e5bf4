#include <gtest/gtest.h>

#include "sim/pick_place_env.h"
#include "sim/subtask.h"
#include "sim/world_layout.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

TEST(ComputeReward, IsMinusTheEuclideanDistance) {
  EXPECT_DOUBLE_EQ(compute_reward({0, 0, 0}, {3, 4, 0}), -5.0);
  EXPECT_DOUBLE_EQ(compute_reward({1, 2, 3}, {1, 2, 3}), 0.0);
}

TEST(TaskSuccess, JudgedByTheObjectWithinFiveCentimetres) {
  const Eigen::Vector3d goal(1.3, 0.75, 0.5);
  EXPECT_TRUE(is_task_success(goal + Eigen::Vector3d(0.049, 0, 0), goal));
  EXPECT_FALSE(is_task_success(goal + Eigen::Vector3d(0.051, 0, 0), goal));
}

TEST(StepReward, UsesTheAchievedGoalOfTheObjectiveAndThePassedGoal) {
  PickPlaceEnv env(testing::world());
  env.reset(21);
  const Goal goal(1.0, 0.5, 0.6);
  const Action still{0, 0, 0, 1};
  const StepResult a = env.step(still, goal, Objective::kApproach);
  EXPECT_EQ(a.achieved_goal, gripper_position(a.observation));
  EXPECT_DOUBLE_EQ(a.reward, -(gripper_position(a.observation) - goal).norm());
  const StepResult r = env.step(still, goal, Objective::kRetract);
  EXPECT_EQ(r.achieved_goal, object_position(r.observation));
  EXPECT_DOUBLE_EQ(r.reward, -(object_position(r.observation) - goal).norm());
  const StepResult t = env.step(still, goal, Objective::kTask);
  EXPECT_EQ(t.achieved_goal, object_position(t.observation));
  EXPECT_FALSE(t.objective_done);  // the whole task never terminates early
}

// The original code scored experts by the gripper: a gripper at the goal with the object
// elsewhere is not a success here.
TEST(StepSuccess, GripperAtTheGoalWithoutTheObjectIsNoSuccess) {
  PickPlaceEnv env(testing::world());
  // A goal high in the air: the gripper can get there without dragging the object along.
  std::uint64_t seed = 0;
  while (env.reset(seed), env.episode_goal().z() < layout::kTableTop_z + 0.12) ++seed;
  StepResult r;
  for (int t = 0; t < 25; ++t) {
    const Eigen::Vector3d error = env.episode_goal() - gripper_position(env.observation());
    const Eigen::Vector3d move = (6 * error).cwiseMax(-1).cwiseMin(1);
    r = env.step(Action{move.x(), move.y(), move.z(), 1}, env.episode_goal(), Objective::kTask);
  }
  ASSERT_LT((gripper_position(r.observation) - env.episode_goal()).norm(), 0.03);
  EXPECT_GT((object_position(r.observation) - env.episode_goal()).norm(),
            layout::kTaskSuccessDistance);
  EXPECT_FALSE(r.task_success);
}

TEST(StepSuccess, ObjectAtTheGoalIsASuccess) {
  PickPlaceEnv env(testing::world());
  env.reset(5);
  // Teleport the object onto the goal (the goal may be in the air: it will fall, so read
  // success on the very next step with a goal at rest height).
  mjData* d = env.mj_data();
  const auto& ids = env.world().ids();
  const Eigen::Vector3d target(1.40, 0.70,
                               layout::kTableTop_z + env.world().object_spec().half_height_m);
  for (int k = 0; k < 3; ++k) d->qpos[ids.object_qpos + k] = target(k);
  const Goal episode_goal = env.episode_goal();
  const StepResult r = env.step(Action{0, 0, 0, 1}, target, Objective::kRetract);
  EXPECT_EQ(r.task_success, (object_position(r.observation) - episode_goal).norm() < 0.05);
  EXPECT_NEAR(r.reward, -(object_position(r.observation) - target).norm(), 1e-12);
  EXPECT_GT(r.reward, -0.005);  // the object sits where it was put
}

}  // namespace
}  // namespace pnp::sim
