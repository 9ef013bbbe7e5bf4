#include "services/sim/env_registry.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "common/error.h"
#include "sim/pick_place_env.h"

namespace pnp::services {
namespace {

using std::chrono::seconds;

TEST(EnvRegistry, BatchesOfOneWorldShareItsCompiledModel) {
  EnvRegistry registry;
  const auto a =
      registry.create(sim::Robot::kPanda, sim::ObjectShape::kBlock, sim::WorldProfile::kGym,
                      sim::Actuation::kMocap, 1, 2, seconds(60));
  const auto b =
      registry.create(sim::Robot::kPanda, sim::ObjectShape::kBlock, sim::WorldProfile::kGym,
                      sim::Actuation::kMocap, 2, 3, seconds(60));
  const auto c =
      registry.create(sim::Robot::kPanda, sim::ObjectShape::kCylinder, sim::WorldProfile::kGym,
                      sim::Actuation::kMocap, 3, 1, seconds(60));
  EXPECT_EQ(registry.get(a)->world.get(), registry.get(b)->world.get());
  EXPECT_NE(registry.get(a)->world.get(), registry.get(c)->world.get());
  EXPECT_EQ(registry.get(c)->world->object(), sim::ObjectShape::kCylinder);
  EXPECT_EQ(registry.environments(), 6);
  // A closed batch leaves the shared world to the others.
  registry.close(a);
  const auto batch = registry.get(b);
  batch->reset(0);
  EXPECT_EQ(static_cast<const sim::PickPlaceEnv&>(*batch->envs[0]).world().mj(),
            batch->world->mj());
  EXPECT_EQ(registry.environments(), 4);
}

TEST(EnvRegistry, RefusesAnOversizedBatchNamingCount) {
  EnvRegistry registry;
  try {
    registry.create(sim::Robot::kPanda, sim::ObjectShape::kBlock, sim::WorldProfile::kGym,
                    sim::Actuation::kMocap, 1, EnvRegistry::kMaxBatch + 1, seconds(60));
    FAIL() << "a batch of 65 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("count"), std::string::npos) << e.what();
  }
  EXPECT_EQ(registry.environments(), 0);
}

// Ids come from a counter: a batch belongs to the principal that created it, and to any
// other it does not exist.
TEST(EnvRegistry, ABatchIsInvisibleToEveryPrincipalButItsCreator) {
  EnvRegistry registry;
  const auto id =
      registry.create(sim::Robot::kPanda, sim::ObjectShape::kBlock, sim::WorldProfile::kGym,
                      sim::Actuation::kMocap, 1, 2, seconds(60), "approach");
  for (const std::string stranger : {"retract", ""}) {
    EXPECT_THROW(
        try { registry.get(id, stranger); } catch (const Error& e) {
          EXPECT_EQ(e.code(), ErrorCode::kNotFound);
          throw;
        },
        Error);
    EXPECT_THROW(registry.close(id, stranger), Error);
  }
  EXPECT_EQ(registry.environments(), 2);
  EXPECT_EQ(registry.get(id, "approach")->envs.size(), 2u);
  registry.close(id, "approach");
  EXPECT_EQ(registry.environments(), 0);
}

TEST(EnvRegistry, OnePrincipalHoldsAtMostHalfTheEnvironments) {
  EnvRegistry registry;
  const auto create = [&](const std::string& who) {
    return registry.create(sim::Robot::kPanda, sim::ObjectShape::kBlock, sim::WorldProfile::kGym,
                           sim::Actuation::kMocap, 1, EnvRegistry::kMaxBatch, seconds(60), who);
  };
  const auto first = create("greedy");
  create("greedy");  // 128: its share
  try {
    create("greedy");
    FAIL() << "a principal was given more than its share";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
    EXPECT_NE(std::string(e.what()).find("one principal may hold"), std::string::npos) << e.what();
  }
  // Another principal still finds the rest; the share frees as batches close.
  create("trainer");
  registry.close(first, "greedy");
  create("greedy");
  EXPECT_EQ(registry.environments(), 192);
}

// The expiry sweep (the server's housekeeping thread) reads what calls using a batch write
// under the batch's own lock: run both at once (ThreadSanitizer judges it; it found the
// timestamp unsynchronised).
TEST(EnvRegistry, ExpiryRunsWhileABatchIsInUse) {
  EnvRegistry registry;
  const auto id =
      registry.create(sim::Robot::kPanda, sim::ObjectShape::kBlock, sim::WorldProfile::kGym,
                      sim::Actuation::kMocap, 1, 1, seconds(60));
  std::atomic<bool> done{false};
  std::jthread sweeper([&] {
    while (!done) registry.expire(std::chrono::steady_clock::now());
  });
  const auto batch = registry.get(id);
  for (int i = 0; i < 1000; ++i) {
    std::lock_guard lock(batch->mutex);
    batch->touch();
  }
  done = true;
  sweeper.join();
  EXPECT_EQ(registry.environments(), 1) << "a batch in use does not expire";
  EXPECT_EQ(registry.expire(std::chrono::steady_clock::now() + seconds(61)), 1);
}

}  // namespace
}  // namespace pnp::services
