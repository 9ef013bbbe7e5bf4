#include "sim/task_sampler.h"

#include <gtest/gtest.h>

#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

TEST(TaskSampler, ObjectAndGoalStayInTheirRegions) {
  Rng rng(123);
  const double half_height = 0.025;
  const double rest = layout::kTableTop_z + half_height;
  int raised = 0;
  constexpr int n = 20000;
  for (int i = 0; i < n; ++i) {
    const EpisodeLayout e = sample_episode_layout(rng, half_height);
    const Eigen::Vector2d object_offset = e.object.head<2>() - layout::kGripperStart.head<2>();
    ASSERT_LE(object_offset.cwiseAbs().maxCoeff(), layout::kObjectRange);
    ASSERT_GE(object_offset.norm(), layout::kObjectMinDistance);
    ASSERT_DOUBLE_EQ(e.object.z(), rest);
    const Eigen::Vector2d goal_offset = e.goal.head<2>() - layout::kGripperStart.head<2>();
    ASSERT_LE(goal_offset.cwiseAbs().maxCoeff(), layout::kGoalRange);
    ASSERT_GE(e.goal.z(), rest);
    ASSERT_LE(e.goal.z(), rest + layout::kGoalMaxHeight);
    raised += e.goal.z() > rest ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(raised) / n, layout::kGoalAirProbability, 0.02);
}

TEST(TaskSampler, SameGeneratorStateSameLayout) {
  Rng a(9), b(9);
  const EpisodeLayout x = sample_episode_layout(a, 0.03);
  const EpisodeLayout y = sample_episode_layout(b, 0.03);
  EXPECT_EQ(x.object, y.object);
  EXPECT_EQ(x.goal, y.goal);
}

}  // namespace
}  // namespace pnp::sim
