#include "serving/actor_batcher.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "common/error.h"
#include "common/rng.h"
#include "rl/ddpg_her_agent.h"

namespace pnp::serving {
namespace {

struct Fixture {
  rl::DdpgHerAgent agent;

  static rl::DdpgHerConfig config() {
    rl::DdpgHerConfig c;  // 3 x 256: the size served in practice
    return c;
  }
  explicit Fixture(Rng rng = Rng(11)) : agent(config(), rng) {
    std::vector<sim::Observation> obs{sim::Observation::Constant(0.3),
                                      sim::Observation::Constant(-0.2)};
    std::vector<sim::Goal> goals{sim::Goal(1, 0.7, 0.5), sim::Goal(1.2, 0.8, 0.4)};
    agent.update_normalizers(obs, goals);
  }
  ActorBatcher batcher(int max_batch = ActorBatcher::kDefaultMaxBatch) const {
    return ActorBatcher(agent.actor(), agent.observation_normalizer(), agent.goal_normalizer(),
                        agent.config().clip_obs, max_batch);
  }
};

sim::Observation observation_for(int k) {
  sim::Observation o;
  for (int i = 0; i < sim::kObservationSize; ++i) o(i) = 0.05 * ((k * 7 + i * 3) % 19) - 0.4;
  return o;
}
sim::Goal goal_for(int k) {
  return sim::Goal(1.0 + 0.01 * k, 0.75, 0.45);
}

void expect_near(const sim::Action& a, const sim::Action& b) {
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(a(i), b(i), 1e-5) << "component " << i;
}

TEST(ActorBatcher, LoneRequestMatchesTheUnbatchedActor) {
  Fixture f;
  auto batcher = f.batcher();
  auto snapshot = f.agent.snapshot();
  for (int k = 0; k < 5; ++k) {
    expect_near(batcher.act(observation_for(k), goal_for(k)),
                snapshot.act(observation_for(k), goal_for(k)));
  }
  const BatchStats s = batcher.stats();
  EXPECT_EQ(s.requests, 5u);
  EXPECT_EQ(s.batches, 5u);
  EXPECT_EQ(s.largest_batch, 1);
}

// Requests queued while a batch runs go together in the next one, and each gets the
// action of its own input.
TEST(ActorBatcher, QueuedRequestsRunAsOneBatchWithTheirOwnAnswers) {
  Fixture f;
  auto batcher = f.batcher();
  constexpr int kClients = 6;
  std::vector<sim::Action> answers(kClients);
  std::vector<std::jthread> clients;
  {
    ActorBatcher::Pause pause(batcher);
    for (int k = 0; k < kClients; ++k) {
      clients.emplace_back([&, k] {
        answers[static_cast<std::size_t>(k)] = batcher.act(observation_for(k), goal_for(k));
      });
    }
    while (batcher.waiting() < kClients) std::this_thread::yield();
  }
  clients.clear();  // joins
  const BatchStats s = batcher.stats();
  EXPECT_EQ(s.batches, 1u);
  EXPECT_EQ(s.largest_batch, kClients);
  auto snapshot = f.agent.snapshot();
  for (int k = 0; k < kClients; ++k) {
    expect_near(answers[static_cast<std::size_t>(k)],
                snapshot.act(observation_for(k), goal_for(k)));
  }
}

TEST(ActorBatcher, BatchesNeverExceedTheirBound) {
  Fixture f;
  auto batcher = f.batcher(4);
  constexpr int kClients = 10;
  std::vector<sim::Action> answers(kClients);
  std::vector<std::jthread> clients;
  {
    ActorBatcher::Pause pause(batcher);
    for (int k = 0; k < kClients; ++k) {
      clients.emplace_back([&, k] {
        answers[static_cast<std::size_t>(k)] = batcher.act(observation_for(k), goal_for(k));
      });
    }
    while (batcher.waiting() < kClients) std::this_thread::yield();
  }
  clients.clear();
  const BatchStats s = batcher.stats();
  EXPECT_EQ(s.requests, static_cast<std::uint64_t>(kClients));
  EXPECT_EQ(s.batches, 3u);  // 4 + 4 + 2
  EXPECT_EQ(s.largest_batch, 4);
  auto snapshot = f.agent.snapshot();
  for (int k = 0; k < kClients; ++k) {
    expect_near(answers[static_cast<std::size_t>(k)],
                snapshot.act(observation_for(k), goal_for(k)));
  }
}

TEST(ActorBatcher, ManyConcurrentClientsAllGetTheirOwnAnswer) {
  Fixture f;
  auto batcher = f.batcher();
  constexpr int kClients = 8, kEach = 50;
  std::vector<std::vector<sim::Action>> answers(kClients, std::vector<sim::Action>(kEach));
  {
    std::vector<std::jthread> clients;
    for (int c = 0; c < kClients; ++c) {
      clients.emplace_back([&, c] {
        for (int i = 0; i < kEach; ++i) {
          answers[static_cast<std::size_t>(c)][static_cast<std::size_t>(i)] =
              batcher.act(observation_for(c * kEach + i), goal_for(c));
        }
      });
    }
  }
  auto snapshot = f.agent.snapshot();
  for (int c = 0; c < kClients; ++c) {
    for (int i = 0; i < kEach; ++i) {
      expect_near(answers[static_cast<std::size_t>(c)][static_cast<std::size_t>(i)],
                  snapshot.act(observation_for(c * kEach + i), goal_for(c)));
    }
  }
  EXPECT_EQ(batcher.stats().requests, static_cast<std::uint64_t>(kClients * kEach));
}

TEST(ActorBatcher, RefusesANonPositiveBound) {
  Fixture f;
  try {
    f.batcher(0);
    FAIL() << "max_batch 0 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "max_batch: expected a positive batch size, got 0");
  }
}

}  // namespace
}  // namespace pnp::serving
