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
