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

TEST_F(StoreTest, AClaimGivesARunToOneOwnerUntilItsLeaseExpires) {
  RunStore a(path_), b(path_);
  const auto first = a.create_run(spec());
  const auto second = a.create_run(spec());
  a.create_run(spec("retract"));  // another role: never claimed by approach owners
  const auto got_a = a.claim_next("approach", "server-a", 60s);
  ASSERT_TRUE(got_a);
  EXPECT_EQ(got_a->id, first.id) << "oldest first";
  EXPECT_EQ(got_a->state, RunState::kRunning);
  EXPECT_EQ(got_a->owner, "server-a");
  const auto got_b = b.claim_next("approach", "server-b", 60s);
  ASSERT_TRUE(got_b);
  EXPECT_EQ(got_b->id, second.id) << "a held run is never handed out twice";
  EXPECT_FALSE(b.claim_next("approach", "server-c", 60s));
  EXPECT_EQ(b.count_claimable("approach", "server-c"), 0);

  // Only the owner writes the run's curve, checkpoints and state.
  const MetricPoint point{1000, 20, 1.0, 0.5, 0.5, 0.5, 0.1, 0.1, 50};
  EXPECT_EQ(code_of([&] { b.record_evaluation(first.id, point, kBlob, false, {}, "server-b"); }),
            ErrorCode::kAborted);
  EXPECT_EQ(code_of([&] { b.set_state(first.id, RunState::kSucceeded, "", "server-b"); }),
            ErrorCode::kAborted);
  EXPECT_TRUE(b.metrics(first.id).empty()) << "a refused write leaves nothing";
  a.record_evaluation(first.id, point, kBlob, false, {}, "server-a");
  EXPECT_TRUE(a.renew_lease(first.id, "server-a", 60s));
  EXPECT_FALSE(a.renew_lease(first.id, "server-b", 60s));

  // A lease that has expired lets another owner take the run over; the old owner's
  // renewals and writes are then refused.
  EXPECT_TRUE(a.renew_lease(first.id, "server-a", 1ms));
  std::this_thread::sleep_for(5ms);
  const auto taken = b.claim_next("approach", "server-c", 60s);
  ASSERT_TRUE(taken);
  EXPECT_EQ(taken->id, first.id);
  EXPECT_EQ(taken->owner, "server-c");
  EXPECT_FALSE(a.renew_lease(first.id, "server-a", 60s));
  EXPECT_EQ(code_of([&] { a.record_evaluation(first.id, point, kBlob, false, {}, "server-a"); }),
            ErrorCode::kAborted);

  // Anyone may cancel; the owner's next renewal says so; a finished run has no owner.
  const auto cancelled = b.set_state(second.id, RunState::kCancelled);
  EXPECT_TRUE(cancelled.owner.empty());
  EXPECT_FALSE(b.renew_lease(second.id, "server-b", 60s));
  // Released: another owner may take it at once.
  b.release(first.id, "server-c");
  EXPECT_EQ(a.claim_next("approach", "server-a", 60s)->id, first.id);
}

TEST_F(StoreTest, TheLatestCheckpointIsTheOneWithTheMostSteps) {
  RunStore store(path_);
  const auto run = store.create_run(spec());
  const auto later = store.save_checkpoint(run.id, 3000, 0.5, kBlob);
  store.save_checkpoint(run.id, 1000, 0.5, kBlob);  // written after, fewer steps
  EXPECT_EQ(store.latest_checkpoint(run.id)->id, later.id);
  EXPECT_EQ(store.checkpoints(run.id).back().env_steps, 3000);
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

TEST_F(StoreTest, APromotionOfManyIsSeenWholeByAConcurrentReader) {
  RunStore writer(path_);
  std::vector<std::vector<std::int64_t>> sets(2);
  for (auto& set : sets) {
    for (const char* role : {"approach", "manipulate", "retract", "hlc"}) {
      const auto run = writer.create_run(spec(role));
      set.push_back(writer.save_checkpoint(run.id, 1, 0.5, kBlob).id);
    }
  }
  writer.promote(sets[0]);
  std::atomic<bool> done{false};
  std::atomic<int> mixed{0}, reads{0};
  std::thread reader([&] {
    RunStore store(path_, {.access = Access::kReadOnly});
    while (!done) {
      std::set<std::int64_t> seen;
      for (const auto& p : store.promotions()) seen.insert(p.checkpoint_id);
      const bool whole = seen == std::set<std::int64_t>(sets[0].begin(), sets[0].end()) ||
                         seen == std::set<std::int64_t>(sets[1].begin(), sets[1].end());
      if (!whole) ++mixed;
      ++reads;
    }
  });
  for (int round = 0; round < 200; ++round)
    writer.promote(sets[static_cast<std::size_t>(round % 2 == 0)]);
  done = true;
  reader.join();
  EXPECT_GT(reads.load(), 0);
  EXPECT_EQ(mixed.load(), 0);
  // Two of one role: refused, and nothing changes.
  const std::vector<std::int64_t> twice{sets[0][0], sets[1][0]};
  EXPECT_EQ(code_of([&] { writer.promote(twice); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(writer.promoted("approach")->checkpoint_id, sets[0][0]);
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

TEST_F(StoreTest, RetentionKeepsTheLastBestPromotedAndReferencedCheckpoints) {
  RunStore store(path_);
  const auto run = store.create_run(spec());
  std::vector<CheckpointInfo> saved;
  const double success[] = {0.1, 0.9, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7};
  for (int k = 0; k < 8; ++k)
    saved.push_back(store.save_checkpoint(run.id, 1000 * (k + 1), success[k], kBlob));
  store.promote(saved[2].id);
  RunSpec child = spec();
  child.parent_checkpoint_id = saved[3].id;
  store.create_run(child);
  RunSpec chained = spec("manipulate");
  chained.config_json = R"({"checkpoints":{"experts":[)" + std::to_string(saved[4].id) +
                        R"(],"parent":null},"spec":{}})";
  store.create_run(chained);
  const GcReport report = store.prune_checkpoints(run.id, {.keep_last = 2});
  std::set<std::int64_t> left;
  for (const auto& c : store.checkpoints(run.id)) left.insert(c.id);
  EXPECT_EQ(left, (std::set<std::int64_t>{saved[1].id, saved[2].id, saved[3].id, saved[4].id,
                                          saved[6].id, saved[7].id}))
      << "best, promoted, parent, expert of another run, and the last two";
  EXPECT_EQ(report.checkpoints_deleted, 2);
  EXPECT_EQ(report.bytes_deleted, 8);
  EXPECT_EQ(store.latest_checkpoint(run.id)->id, saved[7].id);
  EXPECT_EQ(code_of([&] { store.prune_checkpoints(run.id, {.keep_last = 0}); }),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(store.collect_garbage({.keep_last = 2}).checkpoints_deleted, 0);
}

TEST_F(StoreTest, WeightsSavedBetweenEvaluationsKeepTheirCountersAndAreNeverTheBest) {
  RunStore store(path_);
  const auto run = store.create_run(spec());
  ASSERT_TRUE(store.claim_next("approach", "a", 10s));
  const auto evaluated = store.save_checkpoint(run.id, 1000, 0.0, kBlob, "a");
  EXPECT_FALSE(evaluated.unevaluated);
  EXPECT_EQ(code_of([&] {
              store.save_unevaluated(run.id, 1500, {30, 600, 9, 2}, kBlob, "b");
            }),
            ErrorCode::kAborted)
      << "only the run's owner saves its weights";
  EXPECT_EQ(code_of([&] {
              store.save_unevaluated(run.id, 1500, {-1, 600, 9, 2}, kBlob, "a");
            }),
            ErrorCode::kInvalidArgument);
  const auto stopped = store.save_unevaluated(run.id, 1500, {30, 600, 9.5, 2.25}, kBlob, "a");
  const CheckpointInfo latest = *store.latest_checkpoint(run.id);
  EXPECT_EQ(latest.id, stopped.id);
  EXPECT_EQ(latest.env_steps, 1500);
  ASSERT_TRUE(latest.unevaluated);
  EXPECT_EQ(latest.unevaluated->episodes, 30);
  EXPECT_EQ(latest.unevaluated->updates, 600);
  EXPECT_EQ(latest.unevaluated->wall_s, 9.5);
  EXPECT_EQ(latest.unevaluated->eval_wall_s, 2.25);
  EXPECT_EQ(store.load_checkpoint(stopped.id).blob, kBlob);
  // Retention: the evaluated checkpoint stays the run's best although the unevaluated ones
  // tie with it (success 0) and are later; keep_last 1 keeps the latest.
  store.save_unevaluated(run.id, 1600, {31, 610, 10, 2.25}, kBlob, "a");
  store.prune_checkpoints(run.id, {.keep_last = 1});
  std::set<std::int64_t> left;
  for (const auto& c : store.checkpoints(run.id)) left.insert(c.id);
  EXPECT_EQ(left, (std::set<std::int64_t>{evaluated.id, store.latest_checkpoint(run.id)->id}));
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
