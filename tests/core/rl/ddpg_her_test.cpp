#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <thread>

#include "common/error.h"
#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "rl/seed_streams.h"
#include "rl/subtask_trainer.h"
#include "rl/update_schedule.h"
#include "support/wall_breakdown_expectations.h"

namespace pnp::rl {
namespace {

std::string refusal(const DdpgHerConfig& c) {
  try {
    c.validate();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "accepted";
}

TEST(DdpgHerConfig, OriginalBcPresetChangesOnlyTheNetworksAndSchedule) {
  DdpgHerConfig base;
  base.noise_eps = 0.1;
  const DdpgHerConfig c = original_bc_config(base);
  EXPECT_EQ(c.hidden, (std::vector<int>{128, 128}));
  EXPECT_EQ(c.hidden_activation, nn::Activation::kELU);
  EXPECT_DOUBLE_EQ(c.actor_learning_rate, 1e-4);
  EXPECT_EQ(c.batch_size, 1);
  EXPECT_DOUBLE_EQ(c.updates_per_transition, 1.0);
  EXPECT_DOUBLE_EQ(c.noise_eps, 0.1) << "exploration stays the base's";
  EXPECT_EQ(refusal(c), "accepted");
}

// One request must not take a server's memory: widths, depth, parameters and batch are
// bounded (rl/network_limits.h), generously beyond the paper's 3 x 256.
TEST(DdpgHerConfig, RefusesNetworksAndBatchesBeyondTheServersBounds) {
  DdpgHerConfig c;
  c.hidden = {1'000'000, 1'000'000};
  EXPECT_EQ(refusal(c), "hidden[0]: expected a width from 1 to 4096, got 1000000");
  c.hidden = std::vector<int>(9, 64);
  EXPECT_EQ(refusal(c), "hidden: expected 1 to 8 hidden layers, got 9");
  c.hidden = {4096, 4096};
  EXPECT_EQ(refusal(c),
            "hidden: expected a network of at most 4000000 parameters, got 16920577 parameters");
  c.hidden = {1024, 1024, 1024};
  EXPECT_EQ(refusal(c), "accepted");
  c = {};
  c.batch_size = 100'000;
  c.buffer_size = 1'000'000;
  EXPECT_EQ(refusal(c), "batch_size: expected 1 to 4096, got 100000");
}

TEST(DdpgHerConfig, RefusesInvalidHyperparametersNamingTheField) {
  DdpgHerConfig c;
  EXPECT_EQ(refusal(c), "accepted");
  c.actor_learning_rate = -1e-3;
  EXPECT_EQ(refusal(c), "actor_learning_rate: expected a positive finite number, got -0.001000");
  c = {};
  c.batch_size = 512;
  c.buffer_size = 256;
  EXPECT_EQ(refusal(c), "batch_size: expected at most buffer_size (256), got 512");
  c = {};
  c.gamma = 1.0;
  EXPECT_EQ(refusal(c), "gamma: expected a value in (0, 1), got 1.000000");
  c = {};
  c.hidden = {256, 0};
  EXPECT_EQ(refusal(c), "hidden[1]: expected a width from 1 to 4096, got 0");
  c = {};
  c.updates_per_transition = -0.4;
  EXPECT_EQ(refusal(c),
            "updates_per_transition: expected a non-negative number (0: updates_per_cycle), got "
            "-0.400000");
  c = {};
  c.demo_bc_weight = std::nan("");  // reachable through the training service's request
  EXPECT_EQ(refusal(c), "demo_bc_weight: expected a non-negative number, got nan");
  c = {};
  c.demo_batch_size = 0;
  EXPECT_EQ(refusal(c), "demo_batch_size: expected a positive integer, got 0.000000");
  c = {};
  c.gripper_commitment = -1;
  EXPECT_EQ(refusal(c), "gripper_commitment: expected a non-negative number, got -1.000000");
}

TEST(ExpertCheckpoint, RoundTripGivesIdenticalActionsAndCorruptionIsRefused) {
  DdpgHerConfig config;
  config.hidden = {32, 32};
  config.hidden_activation = nn::Activation::kELU;  // not the default: the file must carry it
  Rng rng(5);
  DdpgHerAgent agent(config, rng);
  std::vector<sim::Observation> obs{sim::Observation::Constant(0.3),
                                    sim::Observation::Constant(-0.2)};
  std::vector<sim::Goal> goals{sim::Goal(1, 0.7, 0.5), sim::Goal(1.2, 0.8, 0.4)};
  agent.update_normalizers(obs, goals);
  ExpertMeta meta{
      "retract", "ddpg_her", "fetch", "block", "paper", config.hidden, config.hidden_activation,
      true,      200,        5,       0.01,    1000,    0.9,           5,
      "test"};
  const auto bytes = save_expert(meta, agent.actor(), &agent.critic(),
                                 agent.observation_normalizer(), agent.goal_normalizer());
  const LoadedExpert loaded = load_expert(bytes);
  EXPECT_EQ(loaded.meta.role, "retract");
  EXPECT_EQ(loaded.meta.hidden, config.hidden);
  EXPECT_EQ(loaded.meta.hidden_activation, nn::Activation::kELU);
  ActorSnapshot original = agent.snapshot();
  ActorSnapshot restored(loaded.actor, loaded.observation_normalizer, loaded.goal_normalizer,
                         loaded.meta.clip_obs);
  const sim::Observation o = sim::Observation::Constant(0.1);
  EXPECT_EQ(original.act(o, goals[0]), restored.act(o, goals[0]));
  auto corrupted = bytes;
  corrupted[corrupted.size() / 2] ^= 1;
  try {
    load_expert(corrupted);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
  }
}

// n transitions of uniform noise in [-1, 1], rewards made non-positive, none done.
SampledBatch random_batch(std::uint64_t seed, std::size_t n) {
  Rng data(seed);
  SampledBatch batch;
  auto fill = [&](std::vector<float>& v, std::size_t size) {
    v.resize(size);
    for (float& x : v) x = static_cast<float>(data.uniform(-1, 1));
  };
  fill(batch.observation, n * 25);
  fill(batch.next_observation, n * 25);
  fill(batch.goal, n * 3);
  fill(batch.action, n * 4);
  fill(batch.reward, n);
  for (float& r : batch.reward) r = -std::abs(r);
  batch.done.assign(n, 0.0f);
  return batch;
}

// The update's batch halves run on two threads or one; the weights must be identical.
TEST(DdpgHer, UpdateIsIdenticalOnOneOrTwoThreads) {
  DdpgHerConfig config;  // 3 x 256, batch 256: the unpacked kernel on its paths
  Rng rng_a(9), rng_b(9);
  DdpgHerAgent one(config, rng_a, 1), two(config, rng_b, 2);
  const SampledBatch batch = random_batch(10, 256);
  for (int i = 0; i < 5; ++i) {
    const UpdateStats a = one.update(batch), b = two.update(batch);
    EXPECT_EQ(a.critic_loss, b.critic_loss);
  }
  EXPECT_TRUE(std::equal(one.actor().params().begin(), one.actor().params().end(),
                         two.actor().params().begin()));
  EXPECT_TRUE(std::equal(one.critic().params().begin(), one.critic().params().end(),
                         two.critic().params().begin()));
}

// The actor's gripper command for the batch's i-th state.
double gripper_command(ActorSnapshot& actor, const SampledBatch& batch, int i) {
  sim::Observation o;
  for (int k = 0; k < 25; ++k) o(k) = batch.observation[static_cast<std::size_t>(i * 25 + k)];
  const sim::Goal g(batch.goal[static_cast<std::size_t>(i * 3)],
                    batch.goal[static_cast<std::size_t>(i * 3 + 1)],
                    batch.goal[static_cast<std::size_t>(i * 3 + 2)]);
  return actor.act(o, g)(3);
}

double mean_abs_gripper(const DdpgHerAgent& agent, const SampledBatch& batch) {
  ActorSnapshot actor = agent.snapshot();
  double sum = 0;
  for (int i = 0; i < 64; ++i) {
    sum += std::abs(gripper_command(actor, batch, i));
  }
  return sum / 64;
}

// The prior adds gripper_commitment * mean((1 - g^2) where g < 0) to the actor's loss, and training
// with it moves the learned gripper command away from 0; with a scripted gripper it
// changes nothing.
TEST(DdpgHer, GripperCommitmentPushesTheLearnedGripperCommandToAnEnd) {
  DdpgHerConfig config;
  config.hidden = {32, 32};
  config.batch_size = 64;
  config.action_l2 = 0;
  const SampledBatch batch = random_batch(11, 64);
  auto trained = [&](double weight, bool learn_gripper, std::vector<double>* losses) {
    DdpgHerConfig c = config;
    c.gripper_commitment = weight;
    c.learn_gripper = learn_gripper;
    Rng rng(21);
    auto agent = std::make_unique<DdpgHerAgent>(c, rng, 1);
    for (int i = 0; i < 200; ++i) {
      const UpdateStats stats = agent->update(batch);
      if (losses) losses->push_back(stats.actor_loss + stats.mean_q);
    }
    return agent;
  };
  std::vector<double> without, with;
  const auto plain = trained(0, true, &without);
  const auto committed = trained(2.0, true, &with);
  // Before the first step both actors are the same network: the losses differ by the term.
  EXPECT_DOUBLE_EQ(without.front(), 0.0);
  EXPECT_GT(with.front(), 0.0);
  EXPECT_LE(with.front(), 2.0);
  EXPECT_LT(with.back(), 0.2 * with.front()) << "the commands went to the ends";
  EXPECT_GT(mean_abs_gripper(*committed, batch), mean_abs_gripper(*plain, batch) + 0.2);
  const auto scripted = trained(2.0, false, nullptr);
  const auto scripted_plain = trained(0, false, nullptr);
  EXPECT_TRUE(std::equal(scripted->actor().params().begin(), scripted->actor().params().end(),
                         scripted_plain->actor().params().begin()));
}

// The prior counts closing commands only: on the first update its share of the actor's
// loss is the weight times the mean of (1 - g^2) over the commands below 0, where g is
// the untrained actor's command (an opening command must be left to the critic).
TEST(DdpgHer, GripperCommitmentCountsClosingCommandsOnly) {
  DdpgHerConfig config;
  config.hidden = {32, 32};
  config.batch_size = 64;
  config.action_l2 = 0;
  config.gripper_commitment = 2.0;
  const SampledBatch batch = random_batch(12, 64);
  // The first initialisation whose untrained commands take both signs on the batch.
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    Rng probe_rng(seed);
    const DdpgHerAgent probe(config, probe_rng, 1);
    ActorSnapshot actor = probe.snapshot();
    double expected = 0;
    int closing = 0;
    for (int i = 0; i < 64; ++i) {
      const double g = gripper_command(actor, batch, i);
      if (g < 0) {
        expected += 1 - g * g;
        ++closing;
      }
    }
    if (closing == 0 || closing == 64) continue;
    Rng rng(seed);
    DdpgHerAgent agent(config, rng, 1);
    const UpdateStats stats = agent.update(batch);
    EXPECT_NEAR(stats.actor_loss + stats.mean_q, 2.0 * expected / 64, 1e-4)
        << "seed " << seed << ", " << closing << " closing commands of 64";
    return;
  }
  FAIL() << "no initialisation gave commands of both signs";
}

TEST(SubtaskTraining, OnlyTheRetractExpertGetsTheGripperPrior) {
  SubtaskTrainingConfig config;
  config.ddpg.gripper_commitment = 1.5;
  for (const sim::Subtask subtask :
       {sim::Subtask::kApproach, sim::Subtask::kManipulate, sim::Subtask::kRetract}) {
    config.subtask = subtask;
    config.algorithm = ExpertAlgorithm::kDdpgHer;
    EXPECT_EQ(agent_config(config).gripper_commitment,
              subtask == sim::Subtask::kRetract ? 1.5 : 0.0);
    config.algorithm = ExpertAlgorithm::kEndToEnd;
    EXPECT_EQ(agent_config(config).gripper_commitment, 0.0);
  }
}

TEST(DdpgHer, BehaviourCloningFitsTheDemonstratedActions) {
  DdpgHerConfig config;
  config.hidden = {64, 64};
  config.batch_size = 32;
  Rng rng(3);
  DdpgHerAgent agent(config, rng);
  SegmentReplay replay(1000, sim::Objective::kRetract, 0.05);
  std::vector<Transition> demo;
  for (int t = 0; t < 20; ++t) {
    Transition tr;
    tr.observation = sim::Observation::Constant(0.01 * t);
    tr.next_observation = tr.observation;
    tr.goal = sim::Goal(1.3, 0.7, 0.5);
    tr.action = sim::Action(0.5, -0.5, 0.1 * (t % 3), -1.0);
    demo.push_back(tr);
  }
  replay.add_segment(demo);
  SampledBatch batch;
  Rng sample_rng(4);
  replay.sample(32, 0.0, sample_rng, batch);
  const double first = agent.behaviour_clone(batch);
  double last = first;
  for (int i = 0; i < 300; ++i) {
    replay.sample(32, 0.0, sample_rng, batch);
    last = agent.behaviour_clone(batch);
  }
  EXPECT_LT(last, first * 0.1);
}

// A small, fast approach-expert run: 64 x 64 networks, 90% target, 30 evaluation episodes.
SubtaskTrainingConfig small_approach_run(ExpertAlgorithm algorithm, std::uint64_t seed,
                                         long long max_steps) {
  SubtaskTrainingConfig config;
  config.algorithm = algorithm;
  config.subtask = sim::Subtask::kApproach;
  config.seed = seed;
  config.ddpg.hidden = {64, 64};
  config.ddpg.updates_per_cycle = 20;
  config.stop.max_steps = max_steps;
  config.stop.eval_interval_steps = 500;
  config.stop.eval_episodes = 30;
  config.stop.target_success = 0.9;
  config.threads = 2;
  return config;
}

// A fast, fixed-seed version of subtask expert training: the approach expert reaches at
// least 90% subtask (and task) success within a small budget. The budget has slack: the
// float rounding of -march=native differs between CPUs (AVX2, AVX-512), and with it the
// exact curve (4000 steps sufficed on one machine, not on another).
TEST(SubtaskTraining, ApproachExpertLearnsWithinASmallBudget) {
  SubtaskTrainingConfig config = small_approach_run(ExpertAlgorithm::kDdpgHer, 7, 6000);
  config.ddpg.demo_episodes = 0;  // learn from exploration alone
  const auto out = train_subtask_expert(
      sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock)),
      config);
  ASSERT_FALSE(out.result.curve.empty());
  EXPECT_TRUE(out.result.reached) << "final success " << out.result.final_success;
  EXPECT_GE(out.result.curve.back().subtask_success, 0.9);
  EXPECT_GT(out.result.eval_env_steps, 0);
  // The steps reported are the steps of the model that goes on, not of an earlier one.
  EXPECT_EQ(out.result.steps_to_target, out.result.train_env_steps);
}

// The run's wall time by phase: every phase measured, none counted twice (their sum is
// within the run's wall time), evaluation as the stop rule's clock has it, and the
// callbacks that write checkpoints and the store under "report" (each sleeps 30 ms here).
TEST(SubtaskTraining, ItsWallTimeIsBrokenDownByPhase) {
  SubtaskTrainingConfig config = small_approach_run(ExpertAlgorithm::kDdpgHer, 7, 1000);
  config.stop.consecutive = 5;  // runs to the cap: two evaluations
  int evaluations = 0;
  const auto out = train_subtask_expert(
      sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock)),
      config, [&](const CurvePoint&) {
        ++evaluations;
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
      });
  ASSERT_EQ(evaluations, 2);
  expect_a_whole_breakdown(out.result, 0.060);
}

TEST(StopTracker, StepsToTargetAreThoseOfTheConfirmingEvaluation) {
  StopRule rule;
  rule.target_success = 0.9;
  StopTracker tracker(rule);
  TrainingResult result;
  const auto point = [](long long steps) {
    CurvePoint p;
    p.env_steps = steps;
    return p;
  };
  EXPECT_FALSE(tracker.record(point(1000), 0.95, result));
  EXPECT_FALSE(tracker.record(point(2000), 0.80, result));  // the streak breaks
  EXPECT_FALSE(tracker.record(point(3000), 0.92, result));
  EXPECT_TRUE(tracker.record(point(4000), 0.91, result));
  EXPECT_TRUE(result.reached);
  EXPECT_EQ(result.steps_to_target, 4000);
  EXPECT_EQ(result.curve.back().stop_score, 0.91) << "the curve keeps what the rule compared";
  EXPECT_EQ(result.final_score, 0.91);
}

TEST(StopTracker, AResumedRunCountsOnFromWhereItStopped) {
  StopRule rule;
  rule.target_success = 0.9;
  CurvePoint evaluated;
  evaluated.env_steps = 1000;
  evaluated.episodes = 20;
  evaluated.updates = 400;
  evaluated.wall_s = 5;
  evaluated.eval_wall_s = 1;
  evaluated.task_success = 0.95;
  TrainingControl control;
  control.resume_curve = {evaluated};
  {  // stopped at its evaluation: the counters are the curve's last point
    StopTracker tracker(rule);
    TrainingResult result;
    EXPECT_FALSE(tracker.resume(
        control, [](const CurvePoint& p) { return p.task_success; }, result));
    EXPECT_EQ(result.train_env_steps, 1000);
    EXPECT_EQ(result.train_episodes, 20);
    EXPECT_EQ(result.updates, 400);
    EXPECT_EQ(result.wall_s, 5);
    EXPECT_EQ(result.curve.size(), 1u);
  }
  // Stopped between evaluations: the counters saved with its weights, and the streak of
  // the curve still counts (one more success reaches the target).
  control.resume_counters = TrainingCounters{1450, 29, 580, 7.5, 1};
  StopTracker tracker(rule);
  TrainingResult result;
  EXPECT_FALSE(tracker.resume(
      control, [](const CurvePoint& p) { return p.task_success; }, result));
  EXPECT_EQ(result.train_env_steps, 1450);
  EXPECT_EQ(result.train_episodes, 29);
  EXPECT_EQ(result.updates, 580);
  EXPECT_EQ(result.wall_s, 7.5);
  CurvePoint next;
  next.env_steps = 2000;
  EXPECT_TRUE(tracker.record(next, 0.92, result));
  EXPECT_EQ(result.steps_to_target, 2000);
  // Counters behind the curve are refused, naming them.
  control.resume_counters = TrainingCounters{900, 29, 580, 7.5, 1};
  StopTracker behind(rule);
  TrainingResult refused;
  try {
    behind.resume(
        control, [](const CurvePoint& p) { return p.task_success; }, refused);
    ADD_FAILURE() << "counters behind the curve were accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("resume_counters"), std::string::npos) << e.what();
  }
}

TEST(SubtaskTraining, OnlineBehaviourCloningLearnsTheApproachExpert) {
  const SubtaskTrainingConfig config = small_approach_run(ExpertAlgorithm::kBcOnline, 2, 3000);
  const auto out = train_subtask_expert(
      sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock)),
      config);
  EXPECT_TRUE(out.result.reached) << "final success " << out.result.final_success;
  EXPECT_EQ(out.result.curve.front().critic_loss, 0.0) << "behaviour cloning trains no critic";
}

TEST(SubtaskTraining, SameSeedSameLearningCurveAtAnyThreadCount) {
  auto run = [](std::size_t threads) {
    SubtaskTrainingConfig config;
    config.subtask = sim::Subtask::kManipulate;
    config.seed = 3;
    config.ddpg.hidden = {32};
    config.ddpg.updates_per_cycle = 5;
    config.ddpg.batch_size = 32;
    config.ddpg.demo_episodes = 2;
    config.ddpg.demo_pretrain_updates = 10;
    config.stop.max_steps = 300;
    config.stop.eval_interval_steps = 150;
    config.stop.eval_episodes = 6;
    config.threads = threads;
    return train_subtask_expert(
        sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kPanda, sim::ObjectShape::kBlock)),
        config);
  };
  const auto a = run(1), b = run(3);
  ASSERT_EQ(a.result.curve.size(), b.result.curve.size());
  for (std::size_t i = 0; i < a.result.curve.size(); ++i) {
    EXPECT_EQ(a.result.curve[i].env_steps, b.result.curve[i].env_steps);
    EXPECT_EQ(a.result.curve[i].task_success, b.result.curve[i].task_success);
    EXPECT_EQ(a.result.curve[i].critic_loss, b.result.curve[i].critic_loss);
  }
  EXPECT_TRUE(std::equal(a.agent->actor().params().begin(), a.agent->actor().params().end(),
                         b.agent->actor().params().begin()));
}

// The trainer plays the scenes the stop rule asks for: the same training run, evaluated
// on new scenes, scores its first evaluation on other scenes (evaluation feeds no
// learning, so training itself is unchanged).
TEST(SubtaskTraining, FreshEvaluationScenesChangeTheEvaluationNotTheTraining) {
  auto run = [](bool fresh) {
    SubtaskTrainingConfig config;
    config.subtask = sim::Subtask::kApproach;
    config.seed = 4;
    config.ddpg.hidden = {32};
    config.ddpg.updates_per_cycle = 5;
    config.ddpg.batch_size = 32;
    config.ddpg.demo_episodes = 4;  // cloned demonstrations: an expert that reaches sometimes
    config.ddpg.demo_pretrain_updates = 50;
    config.stop.max_steps = 200;
    config.stop.eval_interval_steps = 100;
    config.stop.eval_episodes = 12;
    config.stop.fresh_eval_scenes = fresh;
    config.threads = 2;
    return train_subtask_expert(
        sim::LocalEnvFactory(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock)),
        config);
  };
  const auto fixed = run(false), fresh = run(true);
  ASSERT_EQ(fixed.result.curve.size(), fresh.result.curve.size());
  ASSERT_GE(fixed.result.curve.size(), 2u);
  for (std::size_t i = 0; i < fixed.result.curve.size(); ++i) {
    EXPECT_EQ(fixed.result.curve[i].env_steps, fresh.result.curve[i].env_steps);
    EXPECT_EQ(fixed.result.curve[i].critic_loss, fresh.result.curve[i].critic_loss);
  }
  const auto& a = fixed.result.curve.front();
  const auto& b = fresh.result.curve.front();
  EXPECT_TRUE(a.subtask_mean_steps != b.subtask_mean_steps ||
              a.subtask_success != b.subtask_success || a.task_success != b.task_success)
      << "the same scenes were evaluated: " << a.subtask_mean_steps << " " << a.subtask_success
      << " " << a.task_success;
}

}  // namespace
}  // namespace pnp::rl

namespace pnp::rl {
namespace {

TEST(EvaluationRoundSeed, TheSameScenesEveryRoundOrNewOnesForEach) {
  const std::uint64_t stream = stream_seed(11, Stream::kEvaluation);
  EXPECT_EQ(evaluation_round_seed(stream, false, 0), stream);
  EXPECT_EQ(evaluation_round_seed(stream, false, 7), stream);
  std::set<std::uint64_t> seen{stream, stream_seed(11, Stream::kTrainingEpisodes)};
  for (std::size_t round = 0; round < 50; ++round)
    EXPECT_TRUE(seen.insert(evaluation_round_seed(stream, true, round)).second) << round;
  EXPECT_EQ(evaluation_round_seed(stream, true, 3), evaluation_round_seed(stream, true, 3));
}

TEST(UpdateSchedule, FixedPerCycleByDefault) {
  UpdateSchedule schedule{DdpgHerConfig{}};
  EXPECT_EQ(schedule.updates_for(7), 40);
  EXPECT_EQ(schedule.updates_for(100), 40);
}

TEST(UpdateSchedule, PerTransitionCarriesFractionsSoTheRatioIsExact) {
  DdpgHerConfig c;
  c.updates_per_transition = 0.5;
  UpdateSchedule schedule(c);
  EXPECT_EQ(schedule.updates_for(7), 3);  // 3.5: the half carries over
  EXPECT_EQ(schedule.updates_for(7), 4);  // 0.5 + 3.5
  int total = 0;
  for (int cycle = 0; cycle < 100; ++cycle) total += schedule.updates_for(13);
  EXPECT_EQ(total, 650);
  EXPECT_EQ(schedule.updates_for(0), 0);
}

// Once per cycle (the original) the targets move by polyak whatever the cycle's steps; at
// a rate per n steps, two cycles of u steps move them as far as one of 2u, and n steps as
// far as one original cycle.
TEST(TargetCoefficient, OncePerCycleOrAtTheOriginalsRatePerGradientStep) {
  DdpgHerConfig c;
  EXPECT_DOUBLE_EQ(target_coefficient(c, 7), 0.95);
  EXPECT_DOUBLE_EQ(target_coefficient(c, 40), 0.95);
  c.polyak_every_updates = 40;
  EXPECT_DOUBLE_EQ(target_coefficient(c, 40), 0.95);
  EXPECT_NEAR(target_coefficient(c, 10) * target_coefficient(c, 10), target_coefficient(c, 20),
              1e-15);
  EXPECT_GT(target_coefficient(c, 10), 0.95) << "fewer steps: the targets move less";
  EXPECT_DOUBLE_EQ(target_coefficient(c, 0), 1.0) << "no step: the targets stay";
  c.polyak_every_updates = -1;
  EXPECT_EQ(refusal(c),
            "polyak_every_updates: expected a non-negative integer (0: once per cycle), got "
            "-1.000000");
}

}  // namespace
}  // namespace pnp::rl
