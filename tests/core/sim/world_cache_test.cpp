#include "sim/world_cache.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace pnp::sim {
namespace {

TEST(WorldCache, LoadsEachWorldOnceAndSharesIt) {
  WorldCache cache;
  const auto first = cache.get(Robot::kFetch, ObjectShape::kBlock, WorldProfile::kGym);
  const auto again = cache.get(Robot::kFetch, ObjectShape::kBlock, WorldProfile::kGym);
  EXPECT_EQ(first.get(), again.get());
  EXPECT_EQ(cache.size(), 1u);
  EXPECT_EQ(first->robot(), Robot::kFetch);
  EXPECT_EQ(first->object(), ObjectShape::kBlock);
  EXPECT_EQ(first->profile(), WorldProfile::kGym);
}

TEST(WorldCache, KeysByRobotObjectAndProfile) {
  WorldCache cache;
  const auto base = cache.get(Robot::kFetch, ObjectShape::kBlock, WorldProfile::kGym);
  const auto robot = cache.get(Robot::kPanda, ObjectShape::kBlock, WorldProfile::kGym);
  const auto object = cache.get(Robot::kFetch, ObjectShape::kCylinder, WorldProfile::kGym);
  const auto profile = cache.get(Robot::kFetch, ObjectShape::kBlock, WorldProfile::kPaper);
  EXPECT_NE(base.get(), robot.get());
  EXPECT_NE(base.get(), object.get());
  EXPECT_NE(base.get(), profile.get());
  EXPECT_EQ(robot->robot(), Robot::kPanda);
  EXPECT_EQ(object->object(), ObjectShape::kCylinder);
  EXPECT_EQ(profile->profile(), WorldProfile::kPaper);
  EXPECT_EQ(cache.size(), 4u);
}

TEST(WorldCache, ConcurrentFirstRequestsAllGetTheSameWorld) {
  WorldCache cache;
  constexpr int kThreads = 4;
  std::vector<const WorldModel*> seen(kThreads, nullptr);
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&, t] {
        seen[static_cast<std::size_t>(t)] =
            cache.get(Robot::kPanda, ObjectShape::kBlock, WorldProfile::kGym).get();
      });
  }
  for (const auto* world : seen) EXPECT_EQ(world, seen[0]);
  EXPECT_EQ(cache.size(), 1u);
}

}  // namespace
}  // namespace pnp::sim
