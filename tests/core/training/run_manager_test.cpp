// RunManager: runs train in the background against a real store; refusals store nothing;
// cancellation; a run interrupted by a shutdown resumes from its last checkpoint with its
// learning curve intact.
#include "training/run_manager.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "common/error.h"
#include "tests/core/training/small_runs.h"
#include "training/training_spec.h"

namespace pnp::training {
namespace {

using namespace std::chrono_literals;
using testing::ScratchDir;
using testing::small_spec;

::testing::AssertionResult throws_code(const std::function<void()>& f, ErrorCode code,
                                       const std::string& text) {
  try {
    f();
  } catch (const Error& e) {
    if (e.code() == code && std::string(e.what()).find(text) != std::string::npos)
      return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "threw " << to_string(e.code()) << ": " << e.what();
  }
  return ::testing::AssertionFailure() << "did not throw";
}

// Waits (without a time limit of its own: ctest's applies) until `done` holds.
template <typename Done>
void wait_until(RunManager& manager, Done done) {
  std::uint64_t seen = manager.generation();
  while (!done()) seen = manager.wait_for_change(seen, 100ms);
}

TEST(TrainingSpecJson, RoundTripsEveryField) {
  TrainingSpec spec = small_spec("retract");
  spec.robot = sim::Robot::kPanda;
  spec.object = sim::ObjectShape::kCylinder;
  spec.world = sim::WorldProfile::kGym;
  spec.scripted_gripper = true;
  spec.ddpg.polyak = 0.9;
  spec.a3c.entropy_weight = 0.02;
  spec.stop.fresh_eval_scenes = false;  // not the default, so the round trip shows
  spec.preset = "paper";
  spec.ddpg.polyak_every_updates = 40;
  spec.a3c.network.predicate_inputs = false;
  spec.a3c.network.mask_finished = false;
  spec.a3c.network.chain_prior = 1.5;
  const TrainingSpec back = spec_from_json(to_json(spec));
  EXPECT_EQ(to_json(back), to_json(spec));
  EXPECT_FALSE(back.stop.fresh_eval_scenes);
  EXPECT_EQ(back.preset, "paper");
  EXPECT_EQ(back.ddpg.polyak_every_updates, 40);
  EXPECT_FALSE(back.a3c.network.predicate_inputs);
  EXPECT_FALSE(back.a3c.network.mask_finished);
  EXPECT_EQ(back.a3c.network.chain_prior, 1.5);
  EXPECT_EQ(back.robot, sim::Robot::kPanda);
  EXPECT_EQ(back.world, sim::WorldProfile::kGym);
  EXPECT_EQ(back.ddpg.hidden, (std::vector<int>{32, 32}));
}

TEST(TrainingSpecJson, AnUnknownWorldIsRefusedNamingTheField) {
  EXPECT_TRUE(throws_code(
      [] {
        spec_from_json({{"world", "mujoco"}});
      },
      ErrorCode::kInvalidArgument, "world"));
}

TEST(TrainingSpecJson, RefusesAWrongType) {
  EXPECT_TRUE(throws_code(
      [] {
        spec_from_json({{"stop", {{"max_steps", "many"}}}});
      },
      ErrorCode::kInvalidArgument, "stop.max_steps"));
}

TEST(RunManager, TrainsARunToItsCapRecordingEveryEvaluationWithItsCheckpoint) {
  ScratchDir dir("run_manager_trains");
  RunManager manager({dir.file("pnp.db"), "approach", "test", 2});
  const auto created = manager.create(small_spec(), {});
  EXPECT_EQ(created.state, store::RunState::kPending);
  wait_until(manager, [&] { return store::is_terminal(manager.get(created.id).state); });
  const auto run = manager.get(created.id);
  ASSERT_EQ(run.state, store::RunState::kSucceeded) << run.error;
  const auto metrics = manager.metrics(run.id);
  const auto checkpoints = manager.checkpoints(run.id);
  ASSERT_GE(metrics.size(), 3u);  // at 200, 400 and 600 steps (or past them)
  ASSERT_EQ(checkpoints.size(), metrics.size());
  for (std::size_t i = 0; i < metrics.size(); ++i)
    EXPECT_EQ(checkpoints[i].env_steps, metrics[i].env_steps);
  EXPECT_GE(run.env_steps, 600);
  EXPECT_EQ(run.spec.code_commit, "test");
}

// The steps a run reports are the steps of the checkpoint that goes downstream (its latest:
// what the pipeline promotes and the next expert or the choreographer consumes).
TEST(RunManager, StepsToTargetAreTheConsumedCheckpointsSteps) {
  ScratchDir dir("run_manager_steps_to_target");
  RunManager manager({dir.file("pnp.db"), "approach", "test", 2});
  // SubtaskTraining.ApproachExpertLearnsWithinASmallBudget's run (90% within 6000 steps
  // there), to a lower target: reached on every machine, twice in a row.
  TrainingSpec spec = small_spec("approach", 6000);
  spec.seed = 7;
  spec.ddpg.hidden = {64, 64};
  spec.ddpg.demo_episodes = 0;
  spec.ddpg.updates_per_transition = 0;
  spec.ddpg.updates_per_cycle = 20;
  spec.stop.eval_interval_steps = 500;
  spec.stop.eval_episodes = 30;
  spec.stop.target_success = 0.6;
  const auto created = manager.create(spec, {});
  wait_until(manager, [&] { return store::is_terminal(manager.get(created.id).state); });
  const auto run = manager.get(created.id);
  ASSERT_EQ(run.state, store::RunState::kSucceeded) << run.error;
  ASSERT_TRUE(run.reached) << "the small run did not reach 0.6 twice within 6000 steps";
  const auto checkpoints = manager.checkpoints(run.id);
  ASSERT_FALSE(checkpoints.empty());
  EXPECT_EQ(run.steps_to_target, std::optional<long long>(checkpoints.back().env_steps));
  EXPECT_EQ(run.env_steps, checkpoints.back().env_steps) << "it stopped at the confirming one";
}

TEST(RunManager, RefusalsStoreNothing) {
  ScratchDir dir("run_manager_refusals");
  RunManager manager({dir.file("pnp.db"), "manipulate", "test", 1});
  TrainingSpec wrong_role = small_spec("approach");
  EXPECT_TRUE(throws_code([&] { manager.create(wrong_role, {}); }, ErrorCode::kInvalidArgument,
                          "role: expected \"manipulate\""));
  TrainingSpec bad_lr = small_spec("manipulate");
  bad_lr.ddpg.actor_learning_rate = -1;
  EXPECT_TRUE(throws_code([&] { manager.create(bad_lr, {}); }, ErrorCode::kInvalidArgument,
                          "actor_learning_rate"));
  EXPECT_TRUE(throws_code(
      [&] {
        manager.create(small_spec("manipulate"), {42, {}, {}});
      },
      ErrorCode::kNotFound, "checkpoint 42"));
  EXPECT_TRUE(throws_code(
      [&] {
        manager.create(small_spec("manipulate"), {std::nullopt, {1, 2}, {}});
      },
      ErrorCode::kInvalidArgument, "prefix_checkpoint_ids"));
  // Backward chaining: manipulate is judged with one expert after it, retract.
  EXPECT_TRUE(throws_code(
      [&] {
        manager.create(small_spec("manipulate"), {std::nullopt, {}, {1, 2}});
      },
      ErrorCode::kInvalidArgument,
      "successor_checkpoint_ids: expected 1 ids (the experts after manipulate), got 2 ids"));
  EXPECT_TRUE(throws_code(
      [&] {
        manager.create(small_spec("manipulate"), {std::nullopt, {}, {7}});
      },
      ErrorCode::kNotFound, "checkpoint 7"));
  EXPECT_TRUE(manager.list({}).empty());
}

TEST(RunManager, ChoreographerNeedsPromotedExperts) {
  ScratchDir dir("run_manager_hlc");
  RunManager manager({dir.file("pnp.db"), "hlc", "test", 1});
  EXPECT_TRUE(throws_code([&] { manager.create(small_spec("hlc"), {}); },
                          ErrorCode::kFailedPrecondition, "no promoted approach checkpoint"));
  EXPECT_TRUE(manager.list({}).empty());
}

TEST(RunManager, CancelsARunningRunAndRefusesToCancelItTwice) {
  ScratchDir dir("run_manager_cancel");
  RunManager manager({dir.file("pnp.db"), "approach", "test", 1});
  const auto run = manager.create(small_spec("approach", 1'000'000), {});
  wait_until(manager, [&] { return manager.get(run.id).state == store::RunState::kRunning; });
  manager.cancel(run.id);
  wait_until(manager, [&] { return store::is_terminal(manager.get(run.id).state); });
  EXPECT_EQ(manager.get(run.id).state, store::RunState::kCancelled);
  EXPECT_TRUE(throws_code([&] { manager.cancel(run.id); }, ErrorCode::kFailedPrecondition,
                          "already finished"));
}

TEST(RunManager, CancelsAPendingRunBehindARunningOne) {
  ScratchDir dir("run_manager_cancel_pending");
  RunManager manager({dir.file("pnp.db"), "approach", "test", 1});
  EXPECT_FALSE(manager.load().active.has_value());
  const auto first = manager.create(small_spec("approach", 1'000'000), {});
  const auto second = manager.create(small_spec(), {});
  wait_until(manager, [&] { return manager.load().active_env_steps > 0; });
  const auto load = manager.load();
  EXPECT_EQ(load.active, first.id);
  EXPECT_EQ(load.queued, 1u);
  EXPECT_GT(load.active_steps_per_s, 0.0);
  EXPECT_EQ(manager.cancel(second.id).state, store::RunState::kCancelled);
  manager.cancel(first.id);
  wait_until(manager, [&] { return store::is_terminal(manager.get(first.id).state); });
  EXPECT_TRUE(manager.metrics(second.id).empty());
}

TEST(RunManager, AShutdownLeavesTheRunToResumeFromItsLastCheckpoint) {
  ScratchDir dir("run_manager_resume");
  const std::string db = dir.file("pnp.db");
  std::int64_t id = 0;
  std::vector<store::MetricPoint> before;
  WallBreakdown first_part;
  {
    RunManager first({db, "approach", "test", 1});
    id = first.create(small_spec("approach", 1200), {}).id;
    wait_until(first, [&] { return first.metrics(id).size() >= 2; });
  }  // shut down mid-run
  {
    store::RunStore store(db);
    EXPECT_EQ(store.get_run(id).state, store::RunState::kRunning);
    before = store.metrics(id);
    first_part = store.get_run(id).wall;
  }
  // The part that shut down recorded where its time went: two evaluations at least.
  EXPECT_GT(first_part.eval_s, 0);
  EXPECT_GT(first_part.update_s, 0);
  ASSERT_GE(before.size(), 2u);
  RunManager second({db, "approach", "test", 1});
  wait_until(second, [&] { return store::is_terminal(second.get(id).state); });
  const auto run = second.get(id);
  ASSERT_EQ(run.state, store::RunState::kSucceeded) << run.error;
  const auto after = second.metrics(id);
  ASSERT_GT(after.size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i) {  // the curve so far is intact
    EXPECT_EQ(after[i].env_steps, before[i].env_steps);
    EXPECT_EQ(after[i].task_success, before[i].task_success);
    EXPECT_EQ(after[i].episodes, before[i].episodes);
  }
  EXPECT_GT(after.back().env_steps, before.back().env_steps);
  EXPECT_GE(after.back().env_steps, 1200);
  // It continued from its last checkpoint, not from scratch: episodes keep counting.
  EXPECT_GT(after[before.size()].episodes, before.back().episodes);
  // The run's wall time is both parts': the second part's added to the first's.
  const WallBreakdown& wall = run.wall;
  EXPECT_GT(wall.eval_s, first_part.eval_s);
  EXPECT_GT(wall.rollout_s, first_part.rollout_s);
  EXPECT_NEAR(wall.total_s,
              wall.rollout_s + wall.update_s + wall.eval_s + wall.report_s + wall.other_s, 1e-9);
}

TEST(RunManager, AShutdownOrACancelBetweenEvaluationsKeepsTheTrainersFinalWeights) {
  ScratchDir dir("run_manager_final_weights");
  const std::string db = dir.file("pnp.db");
  TrainingSpec spec = small_spec("approach", 1'000'000);
  spec.stop.eval_interval_steps = 500'000;  // no evaluation before it is stopped
  std::int64_t id = 0;
  {
    RunManager first({db, "approach", "test", 1});
    id = first.create(spec, {}).id;
    wait_until(first, [&] { return first.load().active_env_steps > 0; });
  }  // shut down after at least one round of training
  store::CheckpointInfo saved;
  {
    store::RunStore store(db);
    EXPECT_EQ(store.get_run(id).state, store::RunState::kRunning);
    EXPECT_TRUE(store.metrics(id).empty());
    const auto checkpoints = store.checkpoints(id);
    ASSERT_EQ(checkpoints.size(), 1u) << "the weights at shutdown";
    saved = checkpoints.front();
  }
  ASSERT_TRUE(saved.unevaluated);
  EXPECT_GT(saved.env_steps, 0);
  EXPECT_GT(saved.unevaluated->episodes, 0);
  EXPECT_GT(saved.unevaluated->updates, 0);
  RunManager second({db, "approach", "test", 1});
  // It resumes from those weights and counters, not from scratch.
  wait_until(second, [&] { return second.load().active_env_steps > saved.env_steps; });
  second.cancel(id);
  wait_until(second, [&] { return store::is_terminal(second.get(id).state); });
  EXPECT_EQ(second.get(id).state, store::RunState::kCancelled);
  const auto checkpoints = second.checkpoints(id);
  ASSERT_EQ(checkpoints.size(), 2u) << "and a cancel keeps the weights it stopped with";
  const store::CheckpointInfo& cancelled = checkpoints.back();
  EXPECT_EQ(checkpoints.front().id, saved.id);
  ASSERT_TRUE(cancelled.unevaluated);
  EXPECT_GT(cancelled.env_steps, saved.env_steps);
  EXPECT_GT(cancelled.unevaluated->episodes, saved.unevaluated->episodes);
  EXPECT_GT(cancelled.unevaluated->updates, saved.unevaluated->updates);
  EXPECT_GT(cancelled.unevaluated->wall_s, saved.unevaluated->wall_s);
}

TEST(RunManager, ADamagedLastCheckpointIsPassedOverForTheOneBeforeIt) {
  ScratchDir dir("run_manager_damaged");
  const std::string db = dir.file("pnp.db");
  std::int64_t id = 0;
  {
    RunManager first({db, "approach", "test", 1});
    id = first.create(small_spec("approach", 1200), {}).id;
    wait_until(first, [&] { return first.checkpoints(id).size() >= 2; });
  }  // shut down mid-run
  {
    store::RunStore store(db);
    const auto latest = store.latest_checkpoint(id);
    ASSERT_TRUE(latest);
    store.database().execute("UPDATE checkpoints SET blob = x'00' || substr(blob, 2) WHERE id = " +
                             std::to_string(latest->id));
  }
  RunManager second({db, "approach", "test", 1});
  wait_until(second, [&] { return store::is_terminal(second.get(id).state); });
  const auto run = second.get(id);
  EXPECT_EQ(run.state, store::RunState::kSucceeded) << run.error;
  EXPECT_GE(run.env_steps, 1200);
}

TEST(RunManager, TwoManagersOfARoleShareTheQueueAndNeverARun) {
  ScratchDir dir("run_manager_two");
  const std::string db = dir.file("pnp.db");
  RunManagerOptions options{db, "approach", "test", 1};
  options.lease = std::chrono::milliseconds(500);
  options.owner = "first";
  RunManager first(options);
  options.owner = "second";
  RunManager second(options);
  const auto a = first.create(small_spec("approach", 800), {}).id;
  const auto b = first.create(small_spec("approach", 800), {}).id;
  for (const auto id : {a, b})
    wait_until(first, [&] { return store::is_terminal(first.get(id).state); });
  store::RunStore store(db);
  for (const auto id : {a, b}) {
    EXPECT_EQ(store.get_run(id).state, store::RunState::kSucceeded);
    const auto checkpoints = store.checkpoints(id);  // by steps; their ids must agree
    for (std::size_t k = 1; k < checkpoints.size(); ++k)
      EXPECT_GT(checkpoints[k].id, checkpoints[k - 1].id) << "run " << id << ": two trainers";
  }
}

}  // namespace
}  // namespace pnp::training
