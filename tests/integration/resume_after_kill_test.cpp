// Integration: a training service killed mid-run (SIGKILL, no chance to clean up) or
// stopped (SIGTERM) leaves a consistent store, and when it starts again on the same file
// the same run resumes from its last checkpoint with its learning curve intact. Two
// services of one role on one file never train one run together, and the survivor takes
// over a killed one's run once its lease expires; a store locked by another process for
// 15 s pauses a run, which then finishes. A simulation service killed under a trainer's
// rollouts fails the run with the reason, and a restarted one serves the next run. A store
// that cannot grow fails the run clearly, keeps what it had, and the service says so.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "grpc/health/v1/health.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"
#include "tests/integration/metrics_scrape.h"
#include "tests/integration/store_reader.h"

namespace pnp::integration {
namespace {

namespace tv1 = pnp::train::v1;

constexpr auto kGuard = 180s;  // failure guard on every wait, never an expectation

// A run that trains until cancelled: a step cap far away, evaluations (each with its
// checkpoint) every 200 steps, and learning rates so small that the policy stays as
// initialised, so it cannot reach its target and stop by itself.
tv1::CreateTrainingRunRequest endless_run() {
  tv1::CreateTrainingRunRequest r;
  r.set_role(pnp::common::v1::ROLE_APPROACH);
  r.set_algorithm(tv1::ALGORITHM_DDPG_HER);
  r.set_robot(pnp::common::v1::ROBOT_FETCH);
  r.set_object(pnp::common::v1::OBJECT_SHAPE_BLOCK);
  r.set_seed(7);
  r.mutable_stop()->set_max_steps(10'000'000);
  r.mutable_stop()->set_eval_interval_steps(200);
  r.mutable_stop()->set_eval_episodes(4);
  r.mutable_stop()->set_target_success(1.0);
  auto& d = *r.mutable_ddpg();
  d.add_hidden(32);
  d.add_hidden(32);
  d.set_batch_size(32);
  d.set_buffer_size(20'000);
  d.set_demo_episodes(0);
  d.set_actor_learning_rate(1e-12);
  d.set_critic_learning_rate(1e-12);
  d.set_updates_per_transition(0.25);
  return r;
}

// pnp-train-server --role approach over `db`, and a stub to it.
class Trainer {
 public:
  // A short lease: a killed server's run is taken over (or resumed) within a second.
  // `extra`: more flags (--sim-address ...). `store`: where the store is (default: --db
  // pnp.db in `dir`); `working_dir`: the server's own (empty: the test's).
  Trainer(const TempDir& dir, const std::string& name, const std::vector<std::string>& extra = {},
          std::vector<std::string> store = {}, const std::filesystem::path& working_dir = {})
      : process_(name, args(dir, extra, std::move(store)), dir.path(), {}, working_dir),
        port_(process_.port()) {
    if (port_ > 0) {
      stub_ = tv1::TrainingService::NewStub(
          grpc::CreateChannel(loopback(port_), grpc::InsecureChannelCredentials()));
    }
  }

  ChildProcess& process() { return process_; }
  bool started() const { return port_ > 0; }

  tv1::TrainingRun create(const tv1::CreateTrainingRunRequest& request) {
    tv1::CreateTrainingRunResponse response;
    check(stub_->CreateTrainingRun(context().get(), request, &response), "CreateTrainingRun");
    return response.run();
  }
  tv1::TrainingRun get(std::int64_t run_id) {
    tv1::GetTrainingRunRequest request;
    request.set_run_id(run_id);
    tv1::GetTrainingRunResponse response;
    check(stub_->GetTrainingRun(context().get(), request, &response), "GetTrainingRun");
    return response.run();
  }
  std::vector<tv1::TrainingRun> list() {
    tv1::ListTrainingRunsResponse response;
    check(stub_->ListTrainingRuns(context().get(), {}, &response), "ListTrainingRuns");
    return {response.runs().begin(), response.runs().end()};
  }
  std::vector<tv1::MetricPoint> metrics(std::int64_t run_id) {
    tv1::GetRunMetricsRequest request;
    request.set_run_id(run_id);
    tv1::GetRunMetricsResponse response;
    check(stub_->GetRunMetrics(context().get(), request, &response), "GetRunMetrics");
    return {response.points().begin(), response.points().end()};
  }
  tv1::TrainingRun cancel(std::int64_t run_id) {
    tv1::CancelTrainingRunRequest request;
    request.set_run_id(run_id);
    tv1::CancelTrainingRunResponse response;
    check(stub_->CancelTrainingRun(context().get(), request, &response), "CancelTrainingRun");
    return response.run();
  }

  // Drops the client channel, then SIGTERM: the exit status (empty if the guard passed).
  std::optional<ExitStatus> stop() {
    stub_.reset();
    return process_.terminate_and_wait(kGuard);
  }

 private:
  static std::vector<std::string> args(const TempDir& dir, const std::vector<std::string>& extra,
                                       std::vector<std::string> store) {
    if (store.empty()) store = {"--db", dir.file("pnp.db")};
    std::vector<std::string> a = {std::string(PNP_BIN_DIR) + "/pnp-train-server",
                                  "--role",
                                  "approach",
                                  "--address",
                                  "127.0.0.1:0",
                                  "--threads",
                                  "1",
                                  "--run-lease-s",
                                  "1"};
    a.insert(a.end(), store.begin(), store.end());
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  static std::unique_ptr<grpc::ClientContext> context() {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    return c;
  }
  void check(const grpc::Status& status, const std::string& what) const {
    if (!status.ok()) {
      throw std::runtime_error(what + ": " + std::to_string(status.error_code()) + " " +
                               status.error_message() + "\n" + process_.diagnostics());
    }
  }

  ChildProcess process_;
  int port_ = 0;
  std::unique_ptr<tv1::TrainingService::Stub> stub_;
};

bool finished(const tv1::TrainingRun& run) {
  return run.state() == tv1::RUN_STATE_SUCCEEDED || run.state() == tv1::RUN_STATE_FAILED ||
         run.state() == tv1::RUN_STATE_CANCELLED;
}

// Waits until the run has finished, leaving its last state in `run`; false after the guard.
bool wait_for_end(Trainer& trainer, std::int64_t run_id, tv1::TrainingRun& run) {
  return wait_until(
      [&] {
        run = trainer.get(run_id);
        return finished(run);
      },
      kGuard, 100ms);
}

// Waits until the run has at least `evaluations` evaluations (each with its checkpoint)
// and returns their curve; fails the test if the run finishes first.
std::vector<tv1::MetricPoint> wait_for_evaluations(Trainer& trainer, std::int64_t run_id,
                                                   std::size_t evaluations) {
  std::vector<tv1::MetricPoint> curve;
  tv1::TrainingRun run;
  const bool reached = wait_until(
      [&] {
        run = trainer.get(run_id);
        curve = trainer.metrics(run_id);
        return finished(run) || (curve.size() >= evaluations && run.latest_checkpoint_id() > 0 &&
                                 run.state() == tv1::RUN_STATE_RUNNING);
      },
      kGuard, 50ms);
  EXPECT_TRUE(reached) << trainer.process().diagnostics();
  EXPECT_FALSE(finished(run)) << run.DebugString() << trainer.process().diagnostics();
  return curve;
}

// The run's rows as stored, in curve order.
std::vector<SqlRow> stored_metrics(const StoreReader& store, std::int64_t run_id) {
  return store.rows("SELECT * FROM metrics WHERE run_id = ? ORDER BY env_steps", {run_id});
}

// What the store holds for an interrupted run: the run still RUNNING (to resume), every
// evaluation with its checkpoint (they are written in one transaction, so no kill can
// separate them), intact blobs, a sound file; after a drain (SIGTERM) also the weights the
// trainer stopped with, if it trained past its last evaluation. Returns the curve and the
// last checkpoint's steps and episodes.
struct Interrupted {
  std::vector<SqlRow> metrics;
  long long checkpoint_steps = 0;
  long long checkpoint_episodes = 0;
};
enum class Stop { kKilled, kDrained };
Interrupted check_interrupted_store(const std::string& db, std::int64_t run_id,
                                    const std::vector<tv1::MetricPoint>& seen, Stop how) {
  const StoreReader store(db);
  Interrupted out;
  EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
  EXPECT_EQ(store.text("SELECT state FROM runs WHERE id = ?", {run_id}), "running");
  out.metrics = stored_metrics(store, run_id);
  EXPECT_GE(out.metrics.size(), seen.size());
  // Every evaluation a client was shown is on disk.
  for (const auto& point : seen) {
    EXPECT_EQ(store.integer("SELECT COUNT(*) FROM metrics WHERE run_id = ? AND env_steps = ?",
                            {run_id, point.env_steps()}),
              1)
        << "evaluation at " << point.env_steps() << " lost";
  }
  // Every checkpoint kept has its evaluation (they are written together), except the
  // weights a drained trainer stopped with (marked by their counters, past the last
  // evaluation); the last evaluation's checkpoint is kept, and retention left a few (the
  // last 3 and the best).
  const long long evaluated =
      store.integer("SELECT MAX(env_steps) FROM metrics WHERE run_id = ?", {run_id});
  const long long unevaluated = store.integer(
      "SELECT COUNT(*) FROM checkpoints c WHERE run_id = ? AND NOT EXISTS "
      "(SELECT 1 FROM metrics m WHERE m.run_id = c.run_id AND m.env_steps = c.env_steps)",
      {run_id});
  EXPECT_LE(unevaluated, how == Stop::kDrained ? 1 : 0);
  EXPECT_EQ(store.integer("SELECT COUNT(*) FROM checkpoints WHERE run_id = ? AND "
                          "(episodes IS NULL) != (env_steps <= ?)",
                          {run_id, evaluated}),
            0)
      << "counters are kept with exactly the checkpoints past the last evaluation";
  EXPECT_EQ(store.integer("SELECT COUNT(*) FROM checkpoints WHERE run_id = ? AND env_steps = ?",
                          {run_id, evaluated}),
            1);
  EXPECT_LE(store.integer("SELECT COUNT(*) FROM checkpoints WHERE run_id = ?", {run_id}), 4);
  EXPECT_EQ(store.integer("SELECT COUNT(*) FROM checkpoints WHERE run_id = ? AND "
                          "(length(blob) = 0 OR length(blob) != size_bytes)",
                          {run_id}),
            0);
  out.checkpoint_steps = store.integer(
      "SELECT COALESCE(MAX(env_steps), 0) FROM checkpoints WHERE run_id = ?", {run_id});
  out.checkpoint_episodes = store.integer(
      "SELECT COALESCE(c.episodes, (SELECT m.episodes FROM metrics m WHERE m.run_id = c.run_id "
      "AND m.env_steps = c.env_steps)) FROM checkpoints c WHERE run_id = ? "
      "ORDER BY env_steps DESC LIMIT 1",
      {run_id});
  return out;
}

// Restarts the trainer on the same store and checks that the same run (and no other)
// picks up again: new evaluations past its last checkpoint, continuing its episode
// count; then cancels it, stops the service (exit 0), and checks that the curve from
// before the interruption is on disk unchanged.
void expect_resumes(const TempDir& dir, std::int64_t run_id, const Interrupted& before) {
  Trainer second(dir, "train-second");
  ASSERT_TRUE(second.started()) << second.process().diagnostics();
  const auto runs = second.list();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].run_id(), run_id);

  std::vector<tv1::MetricPoint> curve;
  tv1::TrainingRun run;
  ASSERT_TRUE(wait_until(
      [&] {
        run = second.get(run_id);
        curve = second.metrics(run_id);
        return finished(run) ||
               (!curve.empty() && curve.back().env_steps() > before.checkpoint_steps);
      },
      kGuard, 50ms))
      << second.process().diagnostics();
  ASSERT_FALSE(finished(run)) << run.DebugString() << second.process().diagnostics();
  EXPECT_EQ(run.state(), tv1::RUN_STATE_RUNNING);
  ASSERT_GT(curve.size(), before.metrics.size());
  // The first evaluation after the restart continues from the checkpoint, not from
  // scratch: more steps and more episodes than the last one before it.
  const auto& last_before = curve[before.metrics.size() - 1];
  const auto& first_after = curve[before.metrics.size()];
  EXPECT_LE(last_before.env_steps(), before.checkpoint_steps);
  EXPECT_GT(first_after.env_steps(), before.checkpoint_steps);
  EXPECT_GT(first_after.episodes(), before.checkpoint_episodes);
  EXPECT_GE(before.checkpoint_episodes, last_before.episodes());
  EXPECT_GT(first_after.updates(), last_before.updates());  // counts on, not from 0
  // The run's progress is published apart from the curve: it catches up with it.
  EXPECT_TRUE(wait_until(
      [&] {
        run = second.get(run_id);
        return finished(run) || run.env_steps() >= first_after.env_steps();
      },
      kGuard, 20ms))
      << run.DebugString();
  EXPECT_GE(run.env_steps(), first_after.env_steps());

  second.cancel(run_id);
  ASSERT_TRUE(wait_until([&] { return finished(second.get(run_id)); }, kGuard, 50ms))
      << second.process().diagnostics();
  EXPECT_EQ(second.get(run_id).state(), tv1::RUN_STATE_CANCELLED);
  const auto stopped = second.stop();
  ASSERT_TRUE(stopped) << second.process().diagnostics();
  EXPECT_TRUE(stopped->ok()) << second.process().diagnostics();

  const StoreReader store(dir.file("pnp.db"));
  EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
  EXPECT_EQ(store.text("SELECT state FROM runs WHERE id = ?", {run_id}), "cancelled");
  EXPECT_EQ(store.integer("SELECT COUNT(*) FROM runs"), 1);
  const auto after = stored_metrics(store, run_id);
  ASSERT_GT(after.size(), before.metrics.size());
  for (std::size_t i = 0; i < before.metrics.size(); ++i)
    EXPECT_EQ(after[i], before.metrics[i]) << "row " << i << " changed";
}

TEST(ResumeAfterKill, AKilledTrainerResumesTheSameRunFromItsLastCheckpoint) {
  TempDir dir("resume_after_kill");
  std::int64_t run_id = 0;
  std::vector<tv1::MetricPoint> seen;
  {
    Trainer first(dir, "train-first");
    ASSERT_TRUE(first.started()) << first.process().diagnostics();
    run_id = first.create(endless_run()).run_id();
    ASSERT_GT(run_id, 0);
    seen = wait_for_evaluations(first, run_id, 2);
    ASSERT_GE(seen.size(), 2u);
    first.process().kill();
    const auto status = first.process().wait(kGuard);
    ASSERT_TRUE(status) << first.process().diagnostics();
    EXPECT_EQ(status->describe(), "signal 9");
  }
  const Interrupted before =
      check_interrupted_store(dir.file("pnp.db"), run_id, seen, Stop::kKilled);
  ASSERT_GE(before.metrics.size(), 2u);
  expect_resumes(dir, run_id, before);
}

TEST(ResumeAfterKill, ASigtermMidRunDrainsAndTheRunResumes) {
  TempDir dir("resume_after_sigterm");
  std::int64_t run_id = 0;
  std::vector<tv1::MetricPoint> seen;
  {
    Trainer first(dir, "train-first");
    ASSERT_TRUE(first.started()) << first.process().diagnostics();
    run_id = first.create(endless_run()).run_id();
    ASSERT_GT(run_id, 0);
    seen = wait_for_evaluations(first, run_id, 1);
    ASSERT_GE(seen.size(), 1u);
    const auto status = first.stop();  // while the run trains
    ASSERT_TRUE(status) << first.process().diagnostics();
    EXPECT_TRUE(status->ok()) << first.process().diagnostics();
  }
  const Interrupted before =
      check_interrupted_store(dir.file("pnp.db"), run_id, seen, Stop::kDrained);
  ASSERT_GE(before.metrics.size(), 1u);
  expect_resumes(dir, run_id, before);
}

// The run's curve and checkpoints show one trainer: evaluation steps strictly increase,
// and checkpoints in the order they were written have strictly increasing steps.
void expect_one_trainer(const StoreReader& store, std::int64_t run_id) {
  const auto metric_steps =
      store.rows("SELECT env_steps FROM metrics WHERE run_id = ? ORDER BY rowid", {run_id});
  const auto by_id =
      store.rows("SELECT env_steps FROM checkpoints WHERE run_id = ? ORDER BY id", {run_id});
  const auto by_steps =
      store.rows("SELECT env_steps FROM checkpoints WHERE run_id = ? ORDER BY env_steps", {run_id});
  EXPECT_EQ(by_id, by_steps) << "checkpoints written out of step order: two trainers";
  EXPECT_EQ(store.integer("SELECT COUNT(*) - COUNT(DISTINCT env_steps) FROM checkpoints WHERE "
                          "run_id = ?",
                          {run_id}),
            0);
  EXPECT_FALSE(metric_steps.empty());
}

std::string owner_of(const std::string& db, std::int64_t run_id) {
  return StoreReader(db).text("SELECT COALESCE(owner, '') FROM runs WHERE id = ?", {run_id});
}

// Two trainers of one role, made by `start(name)`, on the store file `db`: each trains its
// own run; after one is SIGKILLed, the survivor takes over its run.
void two_trainers_share_runs_and_a_survivor_takes_over(
    const std::string& db,
    const std::function<std::unique_ptr<Trainer>(const std::string&)>& start) {
  std::unique_ptr<Trainer> a = start("train-a");
  ASSERT_TRUE(a->started()) << a->process().diagnostics();
  std::unique_ptr<Trainer> b_owner = start("train-b");
  Trainer& b = *b_owner;
  ASSERT_TRUE(b.started()) << b.process().diagnostics();
  const std::int64_t first = a->create(endless_run()).run_id();
  const std::int64_t second = a->create(endless_run()).run_id();
  // Each server takes one: both train at once, each under its own owner.
  std::vector<tv1::MetricPoint> seen = wait_for_evaluations(*a, first, 2);
  wait_for_evaluations(b, second, 2);
  const std::string first_owner = owner_of(db, first), second_owner = owner_of(db, second);
  EXPECT_FALSE(first_owner.empty());
  EXPECT_FALSE(second_owner.empty());
  EXPECT_NE(first_owner, second_owner);

  // Kill the first run's server; free the other one by cancelling its run there.
  const bool a_holds_first =
      first_owner.find(":" + std::to_string(a->process().pid()) + ":") != std::string::npos;
  Trainer& survivor = a_holds_first ? b : *a;
  (a_holds_first ? a->process() : b.process()).kill();
  survivor.cancel(second);  // the survivor's own run
  const std::int64_t orphan = first;
  const auto killed_at = std::chrono::steady_clock::now();
  const long long steps_before = seen.back().env_steps();
  std::vector<tv1::MetricPoint> curve;
  ASSERT_TRUE(wait_until(
      [&] {
        curve = survivor.metrics(orphan);
        return finished(survivor.get(orphan)) ||
               (owner_of(db, orphan) != first_owner && !curve.empty() &&
                curve.back().env_steps() > steps_before + 400);
      },
      kGuard, 50ms))
      << survivor.process().diagnostics();
  const double takeover_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  std::printf(
      "[ measured ] the survivor trained the killed server's run within %.1f s (lease 1 s)\n",
      takeover_s);
  ASSERT_FALSE(finished(survivor.get(orphan)));
  EXPECT_NE(owner_of(db, orphan), first_owner);
  for (std::size_t i = 1; i < curve.size(); ++i)
    EXPECT_GT(curve[i].env_steps(), curve[i - 1].env_steps()) << "point " << i;
  survivor.cancel(orphan);
  ASSERT_TRUE(wait_until([&] { return finished(survivor.get(orphan)); }, kGuard, 50ms));
  EXPECT_EQ(survivor.get(orphan).state(), tv1::RUN_STATE_CANCELLED);
  const auto stopped = survivor.stop();
  ASSERT_TRUE(stopped && stopped->ok()) << survivor.process().diagnostics();
  const StoreReader store(db);
  EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
  expect_one_trainer(store, first);
  expect_one_trainer(store, second);
}

TEST(RunOwnership, TwoServersOfARoleNeverShareARunAndASurvivorTakesOverAKilledOnesRun) {
  TempDir dir("two_trainers");
  two_trainers_share_runs_and_a_survivor_takes_over(
      dir.file("pnp.db"),
      [&](const std::string& name) { return std::make_unique<Trainer>(dir, name); });
}

// The same through pnp-store-server: the trainers open no file (each runs in an empty
// directory of its own); only the store server has the database.
TEST(RunOwnership, ThroughTheStoreServerTwoTrainersShareRunsWithNoSharedFile) {
  TempDir dir("two_trainers_store_server");
  std::filesystem::create_directories(dir.path() / "store");
  const std::string db = (dir.path() / "store" / "pnp.db").string();
  ChildProcess store_server(
      "store",
      {std::string(PNP_BIN_DIR) + "/pnp-store-server", "--address", "127.0.0.1:0", "--db", db},
      dir.path(), {}, dir.path() / "store");
  const int store_port = store_server.port();
  ASSERT_GT(store_port, 0) << store_server.diagnostics();
  two_trainers_share_runs_and_a_survivor_takes_over(db, [&](const std::string& name) {
    const auto own = dir.path() / name;
    std::filesystem::create_directories(own);
    return std::make_unique<Trainer>(dir, name, std::vector<std::string>{},
                                     std::vector<std::string>{"--store", loopback(store_port)},
                                     own);
  });
  for (const char* name : {"train-a", "train-b"})
    EXPECT_TRUE(std::filesystem::is_empty(dir.path() / name)) << name << " wrote a file";
}

// Another process holds the write lock for 15 s (a backup, a long migration, an operator's
// sqlite3 shell): the run waits and retries, is never marked failed, and then finishes.
TEST(RunOwnership, AStoreLockedForFifteenSecondsPausesARunWhichThenSucceeds) {
  TempDir dir("locked_store");
  const std::string db = dir.file("pnp.db");
  Trainer trainer(dir, "train");
  ASSERT_TRUE(trainer.started()) << trainer.process().diagnostics();
  auto request = endless_run();
  request.mutable_stop()->set_max_steps(3000);
  const std::int64_t run_id = trainer.create(request).run_id();
  wait_for_evaluations(trainer, run_id, 1);
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &raw), SQLITE_OK);
  std::unique_ptr<sqlite3, int (*)(sqlite3*)> lock(raw, sqlite3_close);
  sqlite3_busy_timeout(raw, 10'000);  // the trainer may be committing an evaluation just now
  ASSERT_EQ(sqlite3_exec(raw, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), SQLITE_OK);
  const auto until = std::chrono::steady_clock::now() + 15s;
  while (std::chrono::steady_clock::now() < until) {
    EXPECT_FALSE(finished(trainer.get(run_id))) << "a run finished while the store was locked";
    std::this_thread::sleep_for(500ms);
  }
  ASSERT_EQ(sqlite3_exec(raw, "ROLLBACK", nullptr, nullptr, nullptr), SQLITE_OK);
  tv1::TrainingRun run;
  ASSERT_TRUE(wait_for_end(trainer, run_id, run)) << trainer.process().diagnostics();
  EXPECT_EQ(run.state(), tv1::RUN_STATE_SUCCEEDED) << run.error();
  EXPECT_GE(run.env_steps(), 3000);
  const auto stopped = trainer.stop();
  ASSERT_TRUE(stopped && stopped->ok()) << trainer.process().diagnostics();
  expect_one_trainer(StoreReader(db), run_id);
}

// The simulation service a trainer rolls out on (--sim-address) is killed mid-run: the
// run fails naming the service and why, the store stays sound, the training service stays
// up, and once the simulation service is back on its port the next run trains through it.
TEST(SimulationFault, AKilledSimulationServiceFailsTheRunClearlyAndARestartedOneServesTheNext) {
  TempDir dir("sim_killed");
  auto sim = std::make_unique<ChildProcess>(
      "sim", std::vector<std::string>{PNP_BIN_DIR "/pnp-sim-server", "--address", "127.0.0.1:0"},
      dir.path());
  const int sim_port = sim->port();
  ASSERT_GT(sim_port, 0) << sim->diagnostics();
  Trainer trainer(dir, "train", {"--sim-address", loopback(sim_port)});
  ASSERT_TRUE(trainer.started()) << trainer.process().diagnostics();
  const std::int64_t run_id = trainer.create(endless_run()).run_id();
  wait_for_evaluations(trainer, run_id, 1);  // rolling out on the service
  sim->kill();
  ASSERT_TRUE(sim->wait(kGuard)) << sim->diagnostics();
  tv1::TrainingRun run;
  ASSERT_TRUE(wait_for_end(trainer, run_id, run)) << trainer.process().diagnostics();
  EXPECT_EQ(run.state(), tv1::RUN_STATE_FAILED);
  EXPECT_NE(run.error().find("simulation service"), std::string::npos) << run.error();
  EXPECT_NE(run.error().find(loopback(sim_port)), std::string::npos) << run.error();
  EXPECT_NE(run.error().find("UNAVAILABLE"), std::string::npos) << run.error();
  EXPECT_EQ(StoreReader(dir.file("pnp.db")).text("PRAGMA integrity_check"), "ok");
  EXPECT_TRUE(trainer.process().running());
  // Back on the same port: the trainer's channel reconnects for the next run.
  sim = std::make_unique<ChildProcess>(
      "sim-again",
      std::vector<std::string>{PNP_BIN_DIR "/pnp-sim-server", "--address", loopback(sim_port)},
      dir.path());
  ASSERT_GT(sim->port(), 0) << sim->diagnostics();
  auto again = endless_run();
  again.mutable_stop()->set_max_steps(400);
  const std::int64_t next = trainer.create(again).run_id();
  ASSERT_TRUE(wait_for_end(trainer, next, run)) << trainer.process().diagnostics();
  EXPECT_EQ(run.state(), tv1::RUN_STATE_SUCCEEDED) << run.error();
  EXPECT_GE(run.env_steps(), 400);
  const auto stopped = trainer.stop();
  ASSERT_TRUE(stopped && stopped->ok()) << trainer.process().diagnostics();
  EXPECT_TRUE(sim->terminate_and_wait(kGuard));
}

// The store's files may not grow past 300 KB (RLIMIT_FSIZE, as a full disk: writes fail
// with an I/O error): the run fails naming the store, nothing is half-written, and the
// training service stays up, answers reads, and reports NOT_SERVING until it can write.
TEST(StoreFault, AStoreThatCannotGrowFailsTheRunAndTheServiceReportsNotServing) {
  TempDir dir("store_full");
  const std::string db = dir.file("pnp.db");
  // SIGXFSZ ignored (and so across exec): a write past the limit fails with EFBIG instead
  // of killing the process.
  ChildProcess server("train",
                      {"/bin/bash", "-c",
                       "trap '' XFSZ; ulimit -f 300; exec \"$0\" --role approach --address "
                       "127.0.0.1:0 --metrics-address 127.0.0.1:0 --threads 1 --db \"$1\"",
                       PNP_BIN_DIR "/pnp-train-server", db},
                      dir.path());
  ASSERT_GT(server.port(), 0) << server.diagnostics();
  auto channel = grpc::CreateChannel(loopback(server.port()), grpc::InsecureChannelCredentials());
  auto training = tv1::TrainingService::NewStub(channel);
  auto health = grpc::health::v1::Health::NewStub(channel);
  const auto call = [] {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + 30s);
    return c;
  };
  // Networks whose first checkpoint (about 1 MB) cannot fit, while creating and claiming
  // the run (a few KB) can.
  auto request = endless_run();
  request.mutable_ddpg()->clear_hidden();
  for (int layer = 0; layer < 3; ++layer) request.mutable_ddpg()->add_hidden(256);
  tv1::CreateTrainingRunResponse created;
  ASSERT_TRUE(training->CreateTrainingRun(call().get(), request, &created).ok());
  tv1::GetTrainingRunRequest get;
  get.set_run_id(created.run().run_id());
  tv1::GetTrainingRunResponse run;
  ASSERT_TRUE(wait_until(
      [&] { return training->GetTrainingRun(call().get(), get, &run).ok() && finished(run.run()); },
      kGuard, 100ms))
      << server.diagnostics();
  EXPECT_EQ(run.run().state(), tv1::RUN_STATE_FAILED);
  EXPECT_NE(run.run().error().find("store " + db), std::string::npos) << run.run().error();
  EXPECT_NE(run.run().error().find("disk I/O error"), std::string::npos) << run.run().error();
  grpc::health::v1::HealthCheckResponse status;
  EXPECT_TRUE(wait_until(
      [&] {
        return health->Check(call().get(), {}, &status).ok() &&
               status.status() == grpc::health::v1::HealthCheckResponse::NOT_SERVING;
      },
      kGuard, 100ms))
      << server.diagnostics();
  EXPECT_NE(server.stderr_text().find("\"store_unwritable\""), std::string::npos);
  EXPECT_TRUE(server.running());
  // What an alert on store write errors reads (deploy/monitoring/alerts.yml).
  const int port = metrics_port(server);
  ASSERT_GT(port, 0) << server.diagnostics();
  std::string exposition;
  EXPECT_TRUE(wait_until(
      [&] {
        exposition = http_get(port, "/metrics");
        return metric_sum(exposition, "pnp_store_fault", {"role=\"approach\""}) == 1.0;
      },
      kGuard, 100ms))
      << exposition;
  EXPECT_GE(metric_sum(exposition, "pnp_store_write_errors_total", {"role=\"approach\""}), 1.0)
      << exposition;
  const StoreReader store(db);
  EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
  // Every evaluation that made it has its checkpoint and every checkpoint its evaluation:
  // they are committed together or not at all.
  EXPECT_EQ(store.text("SELECT COUNT(*) FROM checkpoints c WHERE NOT EXISTS (SELECT 1 FROM "
                       "metrics m WHERE m.run_id = c.run_id AND m.env_steps = c.env_steps)"),
            "0");
  EXPECT_EQ(store.text("SELECT COUNT(*) FROM metrics m WHERE NOT EXISTS (SELECT 1 FROM "
                       "checkpoints c WHERE c.run_id = m.run_id AND c.env_steps = m.env_steps)"),
            "0");
  const auto stopped = server.terminate_and_wait(kGuard);
  ASSERT_TRUE(stopped && stopped->ok()) << server.diagnostics();
}

// A checkpoint file imported into the store while a training server runs (a hierarchy
// trained elsewhere, its file name with a quote) is listed beside the server's runs,
// finished, and is never taken for a run to train.
TEST(RunOwnership, AnImportedCheckpointIsListedAndNeverTrained) {
  TempDir dir("import_listed");
  Trainer trainer(dir, "train");
  ASSERT_TRUE(trainer.started()) << trainer.process().diagnostics();
  const std::filesystem::path file = dir.path() / "my \"best\" approach.ckpt";
  std::filesystem::copy_file(PNP_SOURCE_DIR "/tests/data/panda_block/approach.ckpt", file);
  {
    pnp::store::RunStore store(dir.file("pnp.db"));
    pnp::store::import_checkpoint(store, {"approach", "ddpg_her", "panda", "block", file}, false);
  }
  const auto runs = trainer.list();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].state(), tv1::RUN_STATE_SUCCEEDED);
  EXPECT_GT(runs[0].latest_checkpoint_id(), 0);
  std::this_thread::sleep_for(500ms);  // two polls of the worker (lease 1 s / 4)
  EXPECT_EQ(trainer.get(runs[0].run_id()).state(), tv1::RUN_STATE_SUCCEEDED);
  EXPECT_EQ(trainer.get(runs[0].run_id()).env_steps(), 0) << "never trained";
  const auto stopped = trainer.stop();
  ASSERT_TRUE(stopped && stopped->ok()) << trainer.process().diagnostics();
}

}  // namespace
}  // namespace pnp::integration
