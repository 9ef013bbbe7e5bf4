#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "common/error.h"
#include "rl/a3c_trainer.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/expert_checkpoint.h"
#include "sim/pick_place_env.h"
#include "support/wall_breakdown_expectations.h"

namespace pnp::rl {
namespace {

HlcTrainingOutput short_run(int workers, const ProgressCallback& progress = {}) {
  HlcTrainingConfig config;
  config.seed = 11;
  config.a3c.workers = workers;
  config.a3c.network = {{32, 32}, 8};
  config.stop.max_steps = 600;
  config.stop.eval_interval_steps = 300;
  config.stop.eval_episodes = 4;
  config.eval_threads = 2;
  const sim::ScriptedPolicy scripted;
  return train_choreographer(
      sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock)),
      {&scripted, &scripted, &scripted}, config, progress);
}

// The workers' episodes and gradients run side by side: "rollout" is their time less the
// serialized phases (the gradients' application, evaluation, the callbacks: 30 ms each
// here); nothing is counted twice.
TEST(A3c, ItsWallTimeIsBrokenDownByPhase) {
  int evaluations = 0;
  const auto out = short_run(2, [&](const CurvePoint&) {
    ++evaluations;
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  });
  ASSERT_GE(evaluations, 1);
  expect_a_whole_breakdown(out.result, 0.030 * evaluations);
}

// Workers run concurrently, but gradients are applied in ticket order: the same seed and
// worker count give the same network whatever the scheduling.
TEST(A3c, ReproducibleForAGivenSeedAndWorkerCount) {
  const auto a = short_run(3);
  const auto b = short_run(3);
  ASSERT_EQ(a.result.curve.size(), b.result.curve.size());
  for (std::size_t i = 0; i < a.result.curve.size(); ++i) {
    EXPECT_EQ(a.result.curve[i].env_steps, b.result.curve[i].env_steps);
    EXPECT_EQ(a.result.curve[i].task_success, b.result.curve[i].task_success);
  }
  auto pa = a.net->parameter_blocks();
  auto pb = b.net->parameter_blocks();
  for (std::size_t k = 0; k < pa.size(); ++k)
    EXPECT_TRUE(std::equal(pa[k].begin(), pa[k].end(), pb[k].begin()));
  EXPECT_GE(a.result.train_env_steps, 600);
  EXPECT_EQ(a.result.train_env_steps % 50, 0) << "every choreographer episode runs all 50 steps";
  // The other two workers' episodes in flight at the stop ran, so they count.
  EXPECT_EQ(a.result.train_env_steps, a.result.curve.back().env_steps + 2 * 50);
}

// Same design as the subtask trainer's test: the scene mode changes what the evaluations
// see, never the training (which draws nothing from the evaluation stream).
TEST(A3c, FreshEvaluationScenesChangeTheEvaluationNotTheTraining) {
  auto run = [](bool fresh) {
    HlcTrainingConfig config;
    config.seed = 5;
    config.a3c.workers = 2;
    config.a3c.network = {{32, 32}, 8};
    config.stop.max_steps = 1500;
    config.stop.eval_interval_steps = 500;
    config.stop.eval_episodes = 16;
    config.stop.target_success = 1.0;
    config.stop.fresh_eval_scenes = fresh;
    config.eval_threads = 2;
    const sim::ScriptedPolicy scripted;
    return train_choreographer(
        sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock)),
        {&scripted, &scripted, &scripted}, config);
  };
  const auto fixed = run(false), fresh = run(true);
  ASSERT_EQ(fixed.result.curve.size(), fresh.result.curve.size());
  ASSERT_GE(fixed.result.curve.size(), 2u);
  bool evaluation_differs = false;
  for (std::size_t i = 0; i < fixed.result.curve.size(); ++i) {
    const auto& a = fixed.result.curve[i];
    const auto& b = fresh.result.curve[i];
    EXPECT_EQ(a.env_steps, b.env_steps);
    EXPECT_EQ(a.sampled_success, b.sampled_success) << "training episodes differ";
    evaluation_differs |= a.task_success != b.task_success || a.detail != b.detail;
  }
  EXPECT_TRUE(evaluation_differs) << "both runs evaluated the same scenes";
}

// The first decision of an exploring start was not drawn from the policy: it must add
// nothing to the policy's or the value's loss. Every later decision trains as usual.
TEST(A3c, AnExploringStartsFirstDecisionAddsNoGradient) {
  ChoreographerNet net({{16}, 4});
  Rng init(3);
  net.initialise(init);
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
  sim::ScriptedPolicy scripted;
  Rng choices(1);
  HlcEpisode episode;
  for (std::uint64_t seed = 17; episode.decisions.size() < 2 && seed < 40; ++seed)
    episode =
        run_hlc_episode(env, net, {&scripted, &scripted, &scripted}, seed, true, choices, true);
  ASSERT_GE(episode.decisions.size(), 2u);
  const A3cConfig config;
  auto gradient_norm = [&](HlcEpisode& e) {
    net.zero_grads();
    episode_gradients(net, e, config);
    double sum = 0;
    for (auto block : net.gradient_blocks())
      for (float g : block) sum += static_cast<double>(g) * static_cast<double>(g);
    return std::sqrt(sum);
  };
  HlcEpisode first_only = episode;
  first_only.decisions.resize(1);
  first_only.caches.resize(1);
  EXPECT_EQ(gradient_norm(first_only), 0.0);
  first_only.decisions.front().exploring = false;
  EXPECT_GT(gradient_norm(first_only), 0.0) << "the same decision drawn by the policy trains";
  EXPECT_GT(gradient_norm(episode), 0.0) << "the later decisions still train";
}

TEST(A3c, RefusesInvalidConfiguration) {
  A3cConfig c;
  c.workers = 0;
  EXPECT_THROW(c.validate(), Error);
  c = {};
  c.gamma = 1.5;
  EXPECT_THROW(c.validate(), Error);
  c = {};
  c.exploring_starts = 1.5;
  EXPECT_THROW(c.validate(), Error);
  c = {};
  c.network.chain_prior = std::nan("");
  EXPECT_THROW(c.validate(), Error);
}

TEST(A3c, RefusesWorkersAndNetworksBeyondTheServersBounds) {
  const auto refusal = [](const A3cConfig& c) -> std::string {
    try {
      c.validate();
    } catch (const Error& e) {
      return e.what();
    }
    return "accepted";
  };
  A3cConfig c;
  EXPECT_EQ(refusal(c), "accepted");
  c.workers = 100'000;
  EXPECT_EQ(refusal(c), "workers: expected 1 to 64, got 100000");
  c = {};
  c.network.lstm = 50'000;
  EXPECT_EQ(refusal(c), "network.lstm: expected a width from 1 to 1000, got 50000");
  c = {};
  c.network.trunk = {128, -3};
  EXPECT_EQ(refusal(c), "network.trunk[1]: expected a width from 1 to 4096, got -3");
  c.network.trunk = {};
  EXPECT_EQ(refusal(c), "network.trunk: expected 1 to 8 hidden layers, got 0");
}

// Without predicate inputs the network reads observation and goal only, and a checkpoint
// keeps both options (a checkpoint is served with the inputs it was trained on).
TEST(ChoreographerCheckpoint, KeepsThePaperChoreographersInputsAndMask) {
  ChoreographerNet net({{16, 16}, 4, false, false});
  EXPECT_EQ(net.spec().input_size(), sim::kObservationSize + sim::kGoalSize);
  Rng rng(3);
  net.initialise(rng);
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
  env.reset(5);
  nn::Matrix input;
  net.encode(env.observation(), env.episode_goal(), env.task_state(), input);
  EXPECT_EQ(input.rows(), sim::kObservationSize + sim::kGoalSize);
  const ChoreographerMeta meta{"fetch", "block", "paper", net.spec(), 10, 0.5, 1, "test"};
  const LoadedChoreographer loaded = load_choreographer(save_choreographer(meta, net));
  EXPECT_FALSE(loaded.meta.network.predicate_inputs);
  EXPECT_FALSE(loaded.meta.network.mask_finished);
  EXPECT_EQ(loaded.meta.network, net.spec());
}

TEST(ChoreographerCheckpoint, RoundTripGivesIdenticalDecisionsAndCorruptionIsRefused) {
  ChoreographerNet net({{16, 16}, 4, true, true, 1.5});
  Rng rng(3);
  net.initialise(rng);
  std::vector<double> raw(sim::kObservationSize + sim::kGoalSize, 0.25);
  net.normalizer().update(raw);
  net.normalizer().refresh();
  const ChoreographerMeta meta{"panda", "block", "gym", net.spec(), 1234, 0.97, 8, "test"};
  const auto bytes = save_choreographer(meta, net);
  LoadedChoreographer loaded = load_choreographer(bytes);
  EXPECT_EQ(loaded.meta.robot, "panda");
  EXPECT_EQ(loaded.meta.network, net.spec());
  EXPECT_EQ(loaded.meta.train_env_steps, 1234);
  EXPECT_EQ(loaded.meta.world, "gym");

  // The same two decisions (the LSTM state carries over) from both networks.
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kPanda, sim::ObjectShape::kBlock));
  env.reset(5);
  nn::Matrix input;
  net.encode(env.observation(), env.episode_goal(), env.task_state(), input);
  net.reset_state();
  loaded.net.reset_state();
  for (int decision = 0; decision < 2; ++decision) {
    DecisionCache ca, cb;
    std::array<double, 3> la{}, lb{};
    double va = 0, vb = 0;
    net.step(input, ca, la, va);
    loaded.net.step(input, cb, lb, vb);
    EXPECT_EQ(la, lb);
    EXPECT_EQ(va, vb);
  }

  auto corrupted = bytes;
  corrupted[corrupted.size() / 3] ^= 4;
  try {
    load_choreographer(corrupted);
    FAIL() << "a flipped bit was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
  }
  const std::vector<std::uint8_t> truncated(bytes.begin(), bytes.end() - 9);
  EXPECT_THROW(load_choreographer(truncated), Error);
}

// A checkpoint is served as it says: a chain prior out of range (or NaN) would turn the
// choreographer into a fixed plan, or every choice into NaN.
TEST(ChoreographerCheckpoint, AChainPriorOutOfRangeIsRefusedNamingIt) {
  // NaN is written as JSON null, which the loader refuses as incomplete metadata.
  const std::vector<std::pair<double, std::string>> cases{
      {25.0, "checkpoint chain_prior: expected a logit bonus from -20 to 20, got 25"},
      {std::nan(""), "checkpoint: incomplete metadata"}};
  for (const auto& [prior, message] : cases) {
    ChoreographerNet net({{16}, 4, true, true, prior});
    Rng rng(3);
    net.initialise(rng);
    const ChoreographerMeta meta{"fetch", "block", "gym", net.spec(), 1, 0.5, 1, "test"};
    try {
      load_choreographer(save_choreographer(meta, net));
      ADD_FAILURE() << "a chain prior of " << prior << " was loaded";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST(ChoreographerCheckpoint, AnExpertCheckpointIsRefusedByKind) {
  DdpgHerConfig config;
  config.hidden = {8};
  Rng rng(1);
  DdpgHerAgent agent(config, rng);
  const ExpertMeta meta{
      "approach", "ddpg_her", "fetch", "block", "paper", config.hidden, config.hidden_activation,
      true,       200,        5,       0.01,    10,      0.5,           1,
      "test"};
  const auto bytes = save_expert(meta, agent.actor(), nullptr, agent.observation_normalizer(),
                                 agent.goal_normalizer());
  try {
    load_choreographer(bytes);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("choreographer"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pnp::rl
