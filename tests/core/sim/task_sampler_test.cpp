#include "sim/task_sampler.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

TEST(TaskSampler, ObjectAndGoalStayInTheirRegionsInEveryWorld) {
  for (WorldProfile profile : kAllWorldProfiles) {
    const WorldParameters& w = world_parameters(profile);
    Rng rng(123);
    const double half_height = 0.025;
    const double rest = layout::kTableTop_z + half_height;
    int raised = 0;
    double highest = 0;
    constexpr int n = 20000;
    for (int i = 0; i < n; ++i) {
      const EpisodeLayout e = sample_episode_layout(rng, half_height, w);
      const Eigen::Vector2d object_offset = e.object.head<2>() - w.gripper_start().head<2>();
      ASSERT_LE(object_offset.cwiseAbs().maxCoeff(), w.object_range_m);
      ASSERT_GE(object_offset.norm(), w.object_min_distance_m);
      ASSERT_DOUBLE_EQ(e.object.z(), rest);
      const Eigen::Vector2d goal_offset = e.goal.head<2>() - w.gripper_start().head<2>();
      ASSERT_LE(goal_offset.cwiseAbs().maxCoeff(), w.goal_range_m);
      ASSERT_GE(e.goal.z(), rest);
      ASSERT_LE(e.goal.z(), rest + w.goal_max_height_m);
      raised += e.goal.z() > rest ? 1 : 0;
      highest = std::max(highest, e.goal.z() - rest);
    }
    EXPECT_NEAR(static_cast<double>(raised) / n, w.goal_air_probability, 0.02);
    EXPECT_GT(highest, 0.95 * w.goal_max_height_m) << world_profile_name(profile);
  }
}

TEST(TaskSampler, GymGoalsRiseThreeTimesAsHighAsThePaperWorlds) {
  EXPECT_DOUBLE_EQ(world_parameters(WorldProfile::kPaper).goal_max_height_m, 0.15);
  EXPECT_DOUBLE_EQ(world_parameters(WorldProfile::kGym).goal_max_height_m, 0.45);
}

TEST(TaskSampler, SameGeneratorStateSameLayout) {
  Rng a(9), b(9);
  const WorldParameters& w = world_parameters(WorldProfile::kGym);
  const EpisodeLayout x = sample_episode_layout(a, 0.03, w);
  const EpisodeLayout y = sample_episode_layout(b, 0.03, w);
  EXPECT_EQ(x.object, y.object);
  EXPECT_EQ(x.goal, y.goal);
}

}  // namespace
}  // namespace pnp::sim
