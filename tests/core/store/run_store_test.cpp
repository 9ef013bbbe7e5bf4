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

// A missing id names the store it was looked up in (a server on the wrong file). The
// rest of the store's behaviour is the Store contract (tests/store_contract/).
TEST_F(StoreTest, AMissingCheckpointNamesTheStoreFile) {
  RunStore store(path_);
  try {
    store.load_checkpoint(12345);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_EQ(std::string(e.what()), "checkpoint 12345 not found in store " + path_);
  }
}

// What one checkpoint, one run and one principal may hold: a trainer's identity (or whoever
// broke into its Pod) cannot fill the shared volume.
TEST_F(StoreTest, QuotasBoundACheckpointARunAndAPrincipalsOpenRuns) {
  RunStore store(path_, {},
                 StoreQuotas{.max_checkpoint_bytes = 1000,
                             .max_run_checkpoint_bytes = 2500,
                             .max_open_runs_per_principal = 2});
  const auto first = store.create_run_for(test_spec(), "", "approach");
  const auto second = store.create_run_for(test_spec(), "", "approach");
  EXPECT_EQ(code_of([&] { store.create_run_for(test_spec(), "", "approach"); }),
            ErrorCode::kResourceExhausted);
  store.create_run_for(test_spec(), "", "retract");  // its own quota
  store.create_run(test_spec());                     // no principal: not counted
  store.set_state(second.id, RunState::kCancelled);
  store.create_run_for(test_spec(), "", "approach");  // a finished run frees its place

  const std::vector<std::uint8_t> kilobyte(1000, 7);
  store.save_checkpoint(first.id, 100, 0.1, kilobyte);
  store.save_checkpoint(first.id, 200, 0.2, kilobyte);
  EXPECT_EQ(code_of([&] { store.save_checkpoint(first.id, 300, 0.3, kilobyte); }),
            ErrorCode::kResourceExhausted)
      << "2000 held + 1000 > 2500";
  EXPECT_EQ(code_of([&] {
              store.save_checkpoint(second.id, 100, 0.1, std::vector<std::uint8_t>(1001, 7));
            }),
            ErrorCode::kResourceExhausted)
      << "one checkpoint over 1000";
  EXPECT_EQ(store.checkpoints(first.id).size(), 2u);
  EXPECT_TRUE(store.checkpoints(second.id).empty());
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

// One name for a run's outcome in pnpctl, the dashboard and the Python package (pnpctl said
// "reached" where the dashboard said "succeeded" for the same run).
TEST(RunOutcome, AFinishedRunSaysWhetherItReachedItsTargetOtherRunsTheirState) {
  EXPECT_EQ(run_outcome(RunState::kSucceeded, true), "reached");
  EXPECT_EQ(run_outcome(RunState::kSucceeded, false), "not-reached");
  EXPECT_EQ(run_outcome(RunState::kRunning, false), "running");
  EXPECT_EQ(run_outcome(RunState::kFailed, false), "failed");
  EXPECT_EQ(run_outcome(RunState::kCancelled, true), "cancelled");
}

}  // namespace
}  // namespace pnp::store
