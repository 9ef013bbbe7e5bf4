// The store's durability guarantees: one owner per run, retries while the database is
// busy, commits on disk when acknowledged, ids never reused, opening without the write
// lock, read-only opens, atomic promotions and imports, and bounded growth.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>
#include <vector>

#include "store/checkpoint_import.h"
#include "store/retry.h"
#include "store/run_store.h"
#include "store/schema.h"
#include "tests/core/store/store_fixture.h"

namespace pnp::store {
namespace {

using namespace std::chrono_literals;

const std::vector<std::uint8_t> kBlob{1, 2, 3, 4};

TEST_F(StoreTest, OpensWithSynchronousFullIncrementalVacuumAndABoundedWal) {
  RunStore store(path_);
  EXPECT_EQ(store.database().pragma_int("synchronous"), 2) << "FULL";
  EXPECT_EQ(store.database().pragma_int("auto_vacuum"), 2) << "INCREMENTAL on a new file";
  EXPECT_GT(store.database().pragma_int("journal_size_limit"), 0);
  Database normal(path_, {.sync = Sync::kNormal});  // only pnp-bench-store asks for it
  EXPECT_EQ(normal.pragma_int("synchronous"), 1);
}

TEST_F(StoreTest, AnOlderDatabaseIsMigratedWithItsRowsAndIdsAreNeverReused) {
  std::int64_t old_run = 0, old_checkpoint = 0;
  {
    Database db(path_);
    migrate_to(db, 3);  // as the build before run ownership left it
    db.execute(
        "INSERT INTO runs (role, algorithm, robot, object, seed, config_json, code_commit, state, "
        "created_ms, updated_ms) VALUES ('approach', 'ddpg_her', 'fetch', 'block', 1, '{}', '', "
        "'running', 0, 0)");
    old_run = db.last_insert_id();
    db.execute(
        "INSERT INTO checkpoints (run_id, role, env_steps, eval_success, checksum, "
        "size_bytes, blob, created_ms) VALUES (" +
        std::to_string(old_run) + ", 'approach', 5, 0, 'x', 1, x'01', 0)");
    old_checkpoint = db.last_insert_id();
    db.execute("INSERT INTO promotions VALUES ('approach', " + std::to_string(old_checkpoint) +
               ", 0)");
  }
  RunStore store(path_);
  EXPECT_EQ(store.database().pragma_int("user_version"), schema_version());
  EXPECT_EQ(store.get_run(old_run).state, RunState::kRunning);
  EXPECT_TRUE(store.get_run(old_run).owner.empty());
  EXPECT_EQ(store.get_run(old_run).wall, WallBreakdown{}) << "no part recorded before it was kept";
  EXPECT_EQ(store.checkpoint_info(old_checkpoint).run_id, old_run);
  EXPECT_EQ(store.promoted("approach")->checkpoint_id, old_checkpoint);
  auto fk = store.database().prepare("PRAGMA foreign_key_check");
  EXPECT_FALSE(fk.step());
  EXPECT_EQ(store.database().pragma_int("foreign_keys"), 1);

  // The newest run deleted: its id is not given to the next one.
  const auto newest = store.create_run(spec());
  store.database().execute("DELETE FROM runs WHERE id = " + std::to_string(newest.id));
  EXPECT_GT(store.create_run(spec()).id, newest.id);
}

TEST_F(StoreTest, ACurrentDatabaseOpensWhileAnotherConnectionHoldsTheWriteLock) {
  RunStore{path_};
  Database writer(path_);
  Transaction held(writer);  // BEGIN IMMEDIATE: the write lock, for the whole test
  RunStore store(path_, {.busy_timeout = 50ms});  // no migration: it never waits for the lock
  EXPECT_TRUE(store.list_runs().empty());
  EXPECT_THROW(store.create_run(spec()), BusyError) << "BUSY is its own, retryable, error";
}

TEST_F(StoreTest, AReadOnlyOpenNeverWritesAndSaysSoWhenAskedTo) {
  {
    RunStore writer(path_);
    writer.create_run(spec());
  }
  RunStore reader(path_, {.access = Access::kReadOnly});
  EXPECT_EQ(reader.list_runs().size(), 1u);
  try {
    reader.create_run(spec());
    FAIL() << "a read-only store wrote";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find(path_), std::string::npos) << e.what();
  }
  EXPECT_EQ(code_of([&] {
              RunStore missing((dir_ / "none.db").string(), {.access = Access::kReadOnly});
            }),
            ErrorCode::kNotFound);
  // An older schema cannot be migrated read-only: a clear refusal, not a write.
  const std::string old_path = (dir_ / "old.db").string();
  {
    Database db(old_path);
    migrate_to(db, 2);
  }
  EXPECT_EQ(code_of([&] { RunStore old(old_path, {.access = Access::kReadOnly}); }),
            ErrorCode::kFailedPrecondition);
}

TEST_F(StoreTest, BusyIsRetriedWithBackoffUpToItsBudget) {
  RunStore store(path_, {.busy_timeout = 10ms});
  const auto run = store.create_run(spec());
  std::atomic<bool> locked{false};
  std::thread holder([&] {
    Database other(path_);
    Transaction tx(other);
    locked = true;
    std::this_thread::sleep_for(300ms);
  });  // rolls back and releases the lock after 300 ms
  while (!locked) std::this_thread::yield();
  EXPECT_THROW(store.set_state(run.id, RunState::kRunning), BusyError);
  with_retry(RetryPolicy{.budget = 20s}, [&] { store.set_state(run.id, RunState::kRunning); });
  holder.join();
  EXPECT_EQ(store.get_run(run.id).state, RunState::kRunning);

  // Past the budget the BusyError reaches the caller, having written nothing.
  Database other(path_);
  Transaction tx(other);
  EXPECT_THROW(with_retry(RetryPolicy{.budget = 100ms},
                          [&] { store.set_state(run.id, RunState::kSucceeded); }),
               BusyError);
  // The backoff doubles to its cap and is jittered into [0.5, 1) of it, from its seed.
  const RetryPolicy policy{.first_backoff = 20ms, .max_backoff = 1000ms, .jitter_seed = 3};
  for (int attempt = 0; attempt < 10; ++attempt) {
    const auto full = std::min<long long>(20LL << attempt, 1000);
    const auto pause = retry_backoff(policy, attempt).count();
    EXPECT_GE(pause, full / 2);
    EXPECT_LT(pause, full);
    EXPECT_EQ(pause, retry_backoff(policy, attempt).count());
  }
}

TEST_F(StoreTest, AnImportIsOneTransactionAndItsConfigIsJson) {
  RunStore store(path_);
  const auto dir = dir_ / "hierarchy";
  std::filesystem::create_directories(dir);
  for (const char* role : {"approach", "manipulate", "retract"})
    std::ofstream(dir / (std::string(role) + ".ckpt")) << role;
  // hlc.ckpt missing: nothing of the hierarchy is stored.
  EXPECT_EQ(code_of([&] { import_hierarchy(store, dir, "fetch", "block"); }), ErrorCode::kNotFound);
  EXPECT_TRUE(store.list_runs().empty());
  EXPECT_TRUE(store.promotions().empty());
  std::ofstream(dir / "hlc.ckpt") << "hlc";
  const auto ids = import_hierarchy(store, dir, "fetch", "block");
  EXPECT_EQ(ids.size(), 4u);
  EXPECT_EQ(store.promotions().size(), 4u);
  for (const auto& run : store.list_runs()) EXPECT_EQ(run.state, RunState::kSucceeded);
  // A file name with a quote still makes valid JSON.
  const auto odd = dir / "my \"best\" retract.ckpt";
  std::ofstream(odd) << "x";
  import_checkpoint(store, {"retract", "ddpg_her", "fetch", "block", odd}, false);
  auto valid =
      store.database().prepare("SELECT COUNT(*) FROM runs WHERE NOT json_valid(config_json)");
  valid.step();
  EXPECT_EQ(valid.column_int(0), 0);
}

TEST_F(StoreTest, GarbageCollectionShrinksAFileCreatedWithoutIncrementalVacuum) {
  {
    sqlite3* raw = nullptr;  // as SQLite creates a file by default: auto_vacuum off
    ASSERT_EQ(sqlite3_open(path_.c_str(), &raw), SQLITE_OK);
    sqlite3_exec(raw, "PRAGMA journal_mode = WAL", nullptr, nullptr, nullptr);
    sqlite3_close(raw);
  }
  RunStore store(path_);
  EXPECT_EQ(store.database().pragma_int("auto_vacuum"), 0);
  const auto run = store.create_run(spec());
  const std::vector<std::uint8_t> blob(20000, 7);
  for (int k = 1; k <= 30; ++k) store.save_checkpoint(run.id, 1000 * k, 0.5, blob);
  const std::int64_t pages = store.database().pragma_int("page_count");
  const GcReport report = store.collect_garbage({.keep_last = 1});
  EXPECT_EQ(report.checkpoints_deleted, 29);
  EXPECT_GT(report.pages_freed, pages / 2);
  EXPECT_EQ(store.database().pragma_int("auto_vacuum"), 2) << "converted once";
  EXPECT_EQ(store.checkpoints(run.id).size(), 1u);
}

}  // namespace
}  // namespace pnp::store
