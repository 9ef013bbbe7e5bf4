#include "store/run_store.h"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "common/error.h"
#include "store/schema.h"
#include "tests/core/store/store_fixture.h"

namespace pnp::store {
namespace {

TEST_F(StoreTest, OpensWithWalForeignKeysAndTheCurrentSchema) {
  RunStore store(path_);
  auto mode = store.database().prepare("PRAGMA journal_mode");
  ASSERT_TRUE(mode.step());
  EXPECT_EQ(mode.column_text(0), "wal");
  auto fk = store.database().prepare("PRAGMA foreign_keys");
  ASSERT_TRUE(fk.step());
  EXPECT_EQ(fk.column_int(0), 1);
  auto version = store.database().prepare("PRAGMA user_version");
  ASSERT_TRUE(version.step());
  EXPECT_EQ(version.column_int(0), schema_version());
  RunStore again(path_);  // migrating an up-to-date database is a no-op
  EXPECT_TRUE(again.list_runs().empty());
}

// Servers start together on a new file (a Kubernetes Pod, an integration test): every one
// must open it. Switching a new file to WAL needs an exclusive lock, for which SQLite does
// not always call the busy handler: a server once died at start with "database is
// locked". Many rounds of several connections opening one new file at once.
TEST_F(StoreTest, ConnectionsOpeningOneNewFileAtOnceAllSucceed) {
  for (int round = 0; round < 60; ++round) {
    const std::string path = (dir_ / ("new_" + std::to_string(round) + ".db")).string();
    std::vector<std::thread> threads;
    std::atomic<int> failures{0};
    std::string first_failure;
    std::mutex failure_mutex;
    for (int k = 0; k < 6; ++k) {
      threads.emplace_back([&] {
        try {
          RunStore store(path);
          store.list_runs();
        } catch (const Error& e) {
          if (failures++ == 0) {
            std::lock_guard lock(failure_mutex);
            first_failure = e.what();
          }
        }
      });
    }
    for (auto& t : threads) t.join();
    ASSERT_EQ(failures.load(), 0) << "round " << round << ": " << first_failure;
  }
}

TEST_F(StoreTest, RefusesADatabaseFromANewerBuild) {
  {
    Database db(path_);
    db.execute("PRAGMA user_version = " + std::to_string(schema_version() + 1));
  }
  EXPECT_EQ(code_of([&] { RunStore store(path_); }), ErrorCode::kFailedPrecondition);
}

TEST_F(StoreTest, RunLifecycleAndItsFinalStateIsFinal) {
  RunStore store(path_);
  const RunRecord created = store.create_run(spec());
  EXPECT_EQ(created.state, RunState::kPending);
  EXPECT_EQ(created.spec.config_json, R"({"batch_size":256})");
  EXPECT_EQ(store.set_state(created.id, RunState::kRunning).state, RunState::kRunning);
  const RunRecord done = store.set_state(created.id, RunState::kSucceeded);
  EXPECT_TRUE(done.finished_ms.has_value());
  EXPECT_EQ(code_of([&] { store.set_state(created.id, RunState::kRunning); }),
            ErrorCode::kFailedPrecondition);
  EXPECT_EQ(store.get_run(created.id).state, RunState::kSucceeded) << "a refusal changes nothing";
  EXPECT_EQ(code_of([&] { store.get_run(999); }), ErrorCode::kNotFound);
}

TEST_F(StoreTest, BadRunsAreRefusedNamingTheFieldAndNothingIsWritten) {
  RunStore store(path_);
  RunSpec bad = spec("jump");
  try {
    store.create_run(bad);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("role"), std::string::npos) << e.what();
  }
  bad = spec();
  bad.parent_checkpoint_id = 42;
  EXPECT_EQ(code_of([&] { store.create_run(bad); }), ErrorCode::kNotFound);
  EXPECT_TRUE(store.list_runs().empty());
}

TEST_F(StoreTest, MetricsAreTheLearningCurveAndUpdateTheRunSummary) {
  RunStore store(path_);
  const auto run = store.create_run(spec());
  store.set_state(run.id, RunState::kRunning);
  store.record_metric(run.id, {1000, 50, 2.5, 0.4, 0.5, 0, 0.01, -1.0, 400}, false, std::nullopt);
  store.record_metric(run.id, {2000, 90, 5.0, 0.96, 0.97, 0, 0.01, -1.2, 800}, false, std::nullopt);
  // A resumed run re-evaluates at 2000 steps: the point is replaced, not duplicated.
  store.record_metric(run.id, {2000, 90, 5.5, 0.97, 0.97, 0, 0.01, -1.2, 800}, true, 2000);
  const auto curve = store.metrics(run.id);
  ASSERT_EQ(curve.size(), 2u);
  EXPECT_EQ(curve[0].env_steps, 1000);
  EXPECT_DOUBLE_EQ(curve[1].task_success, 0.97);
  const RunRecord r = store.get_run(run.id);
  EXPECT_EQ(r.env_steps, 2000);
  EXPECT_TRUE(r.reached);
  EXPECT_EQ(r.steps_to_target, 2000);
  store.set_state(run.id, RunState::kCancelled);
  EXPECT_EQ(code_of([&] {
              store.record_metric(run.id, {3000, 1, 1, 1, 1, 0, 0, 0, 1}, true, 2000);
            }),
            ErrorCode::kFailedPrecondition);
  EXPECT_EQ(store.metrics(run.id).size(), 2u);
}

TEST_F(StoreTest, TheStopScoreIsKeptBesideTaskSuccessAndMayBeUnknown) {
  RunStore store(path_);
  const auto run = store.create_run(spec());
  store.set_state(run.id, RunState::kRunning);
  MetricPoint unknown{1000, 50, 2.5, 1.0, 0.7, 0, 0.01, -1.0, 400};  // as before it was kept
  store.record_metric(run.id, unknown, false, std::nullopt);
  EXPECT_FALSE(store.get_run(run.id).last_score);
  MetricPoint scored = unknown;
  scored.env_steps = 2000;
  scored.stop_score = 0.7;  // the lower of task and subtask success: not task success
  store.record_metric(run.id, scored, false, std::nullopt);
  const auto curve = store.metrics(run.id);
  ASSERT_EQ(curve.size(), 2u);
  EXPECT_FALSE(curve[0].stop_score);
  ASSERT_TRUE(curve[1].stop_score);
  EXPECT_DOUBLE_EQ(*curve[1].stop_score, 0.7);
  EXPECT_DOUBLE_EQ(curve[1].task_success, 1.0);
  ASSERT_TRUE(store.get_run(run.id).last_score);
  EXPECT_DOUBLE_EQ(*store.get_run(run.id).last_score, 0.7);
}

TEST_F(StoreTest, CheckpointsRoundTripAndACorruptedBlobIsNeverServed) {
  RunStore store(path_);
  const auto run = store.create_run(spec("retract"));
  const std::vector<std::uint8_t> blob{1, 2, 3, 4, 5, 6, 7, 8};
  const CheckpointInfo saved = store.save_checkpoint(run.id, 5000, 0.9, blob);
  EXPECT_EQ(saved.role, "retract");
  EXPECT_EQ(saved.size_bytes, 8);
  EXPECT_EQ(store.load_checkpoint(saved.id).blob, blob);
  EXPECT_EQ(store.latest_checkpoint(run.id)->id, saved.id);

  // Damage the stored blob behind the store's back: loading and promoting both refuse it.
  store.database().execute("UPDATE checkpoints SET blob = x'0102030405060709' WHERE id = " +
                           std::to_string(saved.id));
  EXPECT_EQ(code_of([&] { store.load_checkpoint(saved.id); }), ErrorCode::kDataLoss);
  EXPECT_EQ(code_of([&] { store.promote(saved.id); }), ErrorCode::kDataLoss);
  EXPECT_FALSE(store.promoted("retract").has_value());
  EXPECT_EQ(code_of([&] { store.save_checkpoint(run.id, 1, 0, {}); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code_of([&] { store.load_checkpoint(12345); }), ErrorCode::kNotFound);
  // A missing id names the store it was looked up in (a server on the wrong file).
  try {
    store.load_checkpoint(12345);
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "checkpoint 12345 not found in store " + path_);
  }
}

TEST_F(StoreTest, PromotionNamesTheCheckpointServingEachRole) {
  RunStore store(path_);
  const auto run = store.create_run(spec("hlc"));
  const std::vector<std::uint8_t> a{1}, b{2};
  const auto first = store.save_checkpoint(run.id, 100, 0.5, a);
  const auto second = store.save_checkpoint(run.id, 200, 0.9, b);
  store.promote(first.id);
  EXPECT_EQ(store.promoted("hlc")->checkpoint_id, first.id);
  store.promote(second.id);
  EXPECT_EQ(store.promoted("hlc")->checkpoint_id, second.id);
  EXPECT_EQ(store.promotions().size(), 1u);
  EXPECT_FALSE(store.promoted("approach").has_value());
  EXPECT_EQ(code_of([&] { store.promoted("nonsense"); }), ErrorCode::kInvalidArgument);
}

TEST_F(StoreTest, ListsNewestFirstWithFiltersAndPaging) {
  RunStore store(path_);
  for (const char* role : {"approach", "manipulate", "approach", "retract"})
    store.create_run(spec(role));
  const auto all = store.list_runs();
  ASSERT_EQ(all.size(), 4u);
  EXPECT_GT(all.front().id, all.back().id);
  RunFilter approach;
  approach.role = "approach";
  EXPECT_EQ(store.list_runs(approach).size(), 2u);
  RunFilter page;
  page.limit = 2;
  const auto first_page = store.list_runs(page);
  page.before_id = first_page.back().id;
  const auto second_page = store.list_runs(page);
  ASSERT_EQ(second_page.size(), 2u);
  EXPECT_LT(second_page.front().id, first_page.back().id);
  page.limit = 0;
  EXPECT_EQ(code_of([&] { store.list_runs(page); }), ErrorCode::kInvalidArgument);
}

TEST_F(StoreTest, ARolledBackTransactionLeavesNothing) {
  RunStore store(path_);
  {
    Transaction tx(store.database());
    store.database().execute(
        "INSERT INTO runs (role, algorithm, robot, object, seed, config_json, code_commit, state, "
        "created_ms, updated_ms) VALUES ('approach', 'x', 'fetch', 'block', 1, '{}', '', "
        "'pending', 0, 0)");
  }  // no commit
  EXPECT_TRUE(store.list_runs().empty());
}

}  // namespace
}  // namespace pnp::store
