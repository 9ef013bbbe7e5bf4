// The Store contract, run against the store in process and the store behind its service.
#include "tests/store_contract/store_contract.h"

#include <atomic>
#include <numeric>
#include <set>
#include <thread>
#include <vector>

namespace pnp::store {
namespace {

using namespace std::chrono_literals;

const std::vector<std::uint8_t> kBlob{1, 2, 3, 4};

TEST_P(StoreContract, RunLifecycleAndItsFinalStateIsFinal) {
  auto s = open();
  Store& store = *s;
  const RunRecord created = store.create_run(spec());
  EXPECT_EQ(created.state, RunState::kPending);
  EXPECT_EQ(created.spec.config_json, R"({"batch_size":256})");
  EXPECT_EQ(created.spec.code_commit, "abc123");
  EXPECT_EQ(store.set_state(created.id, RunState::kRunning).state, RunState::kRunning);
  const RunRecord done = store.set_state(created.id, RunState::kSucceeded);
  EXPECT_TRUE(done.finished_ms.has_value());
  EXPECT_EQ(code_of([&] { store.set_state(created.id, RunState::kRunning); }),
            ErrorCode::kFailedPrecondition);
  EXPECT_EQ(store.get_run(created.id).state, RunState::kSucceeded) << "a refusal changes nothing";
  EXPECT_EQ(code_of([&] { store.get_run(999); }), ErrorCode::kNotFound);
}

TEST_P(StoreContract, BadRunsAreRefusedNamingTheFieldAndNothingIsWritten) {
  auto s = open();
  Store& store = *s;
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

TEST_P(StoreContract, MetricsAreTheLearningCurveAndUpdateTheRunSummary) {
  auto s = open();
  Store& store = *s;
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
  EXPECT_DOUBLE_EQ(curve[1].wall_s, 5.5);
  ASSERT_EQ(store.metrics_after(run.id, 1000).size(), 1u);
  EXPECT_EQ(store.metrics_after(run.id, 1000)[0].env_steps, 2000);
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

TEST_P(StoreContract, TheStopScoreIsKeptBesideTaskSuccessAndMayBeUnknown) {
  auto s = open();
  Store& store = *s;
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

TEST_P(StoreContract, CheckpointsRoundTripAndACorruptedBlobIsNeverServed) {
  auto s = open();
  Store& store = *s;
  const auto run = store.create_run(spec("retract"));
  const std::vector<std::uint8_t> blob{1, 2, 3, 4, 5, 6, 7, 8};
  const CheckpointInfo saved = store.save_checkpoint(run.id, 5000, 0.9, blob);
  EXPECT_EQ(saved.role, "retract");
  EXPECT_EQ(saved.size_bytes, 8);
  EXPECT_EQ(store.load_checkpoint(saved.id).blob, blob);
  EXPECT_EQ(store.latest_checkpoint(run.id)->id, saved.id);
  EXPECT_EQ(store.checkpoint_info(saved.id).checksum, saved.checksum);

  // Damage the stored blob behind the store's back: loading and promoting both refuse it.
  direct().database().execute("UPDATE checkpoints SET blob = x'0102030405060709' WHERE id = " +
                              std::to_string(saved.id));
  EXPECT_EQ(code_of([&] { store.load_checkpoint(saved.id); }), ErrorCode::kDataLoss);
  EXPECT_EQ(code_of([&] { store.promote(saved.id); }), ErrorCode::kDataLoss);
  EXPECT_FALSE(store.promoted("retract").has_value());
  EXPECT_EQ(code_of([&] { store.save_checkpoint(run.id, 1, 0, {}); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code_of([&] { store.load_checkpoint(12345); }), ErrorCode::kNotFound);
  EXPECT_EQ(code_of([&] { store.checkpoint_info(12345); }), ErrorCode::kNotFound);
  EXPECT_FALSE(store.latest_checkpoint(store.create_run(spec()).id));
}

// Larger than one chunk of the service (and not a multiple of it): bytes arrive whole.
TEST_P(StoreContract, AMultiMegabyteCheckpointRoundTripsByteForByte) {
  auto s = open();
  Store& store = *s;
  const auto run = store.create_run(spec());
  std::vector<std::uint8_t> blob(3 * 1024 * 1024 + 17);
  std::iota(blob.begin(), blob.end(), std::uint8_t{0});
  const auto saved = store.save_checkpoint(run.id, 100, 0.5, blob);
  EXPECT_EQ(saved.size_bytes, static_cast<std::int64_t>(blob.size()));
  EXPECT_EQ(store.load_checkpoint(saved.id).blob, blob);
}

TEST_P(StoreContract, PromotionNamesTheCheckpointServingEachRole) {
  auto s = open();
  Store& store = *s;
  const auto run = store.create_run(spec("hlc"));
  const std::vector<std::uint8_t> a{1}, b{2};
  const auto first = store.save_checkpoint(run.id, 100, 0.5, a);
  const auto second = store.save_checkpoint(run.id, 200, 0.9, b);
  store.promote(first.id, "ops");
  EXPECT_EQ(store.promoted("hlc")->checkpoint_id, first.id);
  EXPECT_EQ(store.promoted("hlc")->promoted_by, "ops");
  store.promote(second.id);
  EXPECT_EQ(store.promoted("hlc")->checkpoint_id, second.id);
  EXPECT_EQ(store.promotions().size(), 1u);
  EXPECT_FALSE(store.promoted("approach").has_value());
  EXPECT_EQ(code_of([&] { store.promoted("nonsense"); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code_of([&] { store.promote(98765); }), ErrorCode::kNotFound);
}

TEST_P(StoreContract, ListsNewestFirstWithFiltersAndPaging) {
  auto s = open();
  Store& store = *s;
  for (const char* role : {"approach", "manipulate", "approach", "retract"})
    store.create_run(spec(role));
  const auto all = store.list_runs();
  ASSERT_EQ(all.size(), 4u);
  EXPECT_GT(all.front().id, all.back().id);
  RunFilter approach;
  approach.role = "approach";
  EXPECT_EQ(store.list_runs(approach).size(), 2u);
  RunFilter pending;
  pending.state = RunState::kPending;
  EXPECT_EQ(store.list_runs(pending).size(), 4u);
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

TEST_P(StoreContract, AClaimGivesARunToOneOwnerUntilItsLeaseExpires) {
  auto a_handle = open();
  auto b_handle = open();
  Store& a = *a_handle;
  Store& b = *b_handle;
  const auto first = a.create_run(spec());
  const auto second = a.create_run(spec());
  a.create_run(spec("retract"));  // another role: never claimed by approach owners
  const auto got_a = a.claim_next("approach", "server-a", 60s);
  ASSERT_TRUE(got_a);
  EXPECT_EQ(got_a->id, first.id) << "oldest first";
  EXPECT_EQ(got_a->state, RunState::kRunning);
  EXPECT_EQ(got_a->owner, "server-a");
  EXPECT_TRUE(got_a->lease_expires_ms);
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
  EXPECT_EQ(a.metrics(first.id).size(), 1u);
  EXPECT_EQ(a.checkpoints(first.id).size(), 1u);
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

TEST_P(StoreContract, EachTrainersPartOfTheWallTimeAddsToTheRunsSums) {
  auto s = open();
  Store& store = *s;
  const auto run = store.create_run(spec());
  EXPECT_EQ(run.wall, WallBreakdown{}) << "zero until a part ends";
  ASSERT_TRUE(store.claim_next("approach", "server-a", 60s));
  const WallBreakdown first{.rollout_s = 1.5,
                            .update_s = 6.0,
                            .eval_s = 2.0,
                            .report_s = 0.25,
                            .other_s = 0.25,
                            .total_s = 10.0};
  EXPECT_EQ(store.add_wall_time(run.id, first, "server-a").wall, first);
  // A resumed run's next part adds to the sums; total_s is the phases' sum, never taken
  // from the caller.
  WallBreakdown second{.rollout_s = 0.5,
                       .update_s = 1.0,
                       .eval_s = 1.0,
                       .report_s = 0,
                       .other_s = 0.5,
                       .total_s = 99};
  store.add_wall_time(run.id, second, "server-a");
  const WallBreakdown sum = store.get_run(run.id).wall;
  EXPECT_DOUBLE_EQ(sum.rollout_s, 2.0);
  EXPECT_DOUBLE_EQ(sum.update_s, 7.0);
  EXPECT_DOUBLE_EQ(sum.eval_s, 3.0);
  EXPECT_DOUBLE_EQ(sum.report_s, 0.25);
  EXPECT_DOUBLE_EQ(sum.other_s, 0.75);
  EXPECT_DOUBLE_EQ(sum.total_s, 13.0);

  // Refused, and nothing added: a phase out of range (named), another owner, a finished run.
  for (const double bad : {-1.0, std::nan(""), 2e7}) {
    WallBreakdown wrong = second;
    wrong.eval_s = bad;
    try {
      store.add_wall_time(run.id, wrong, "server-a");
      ADD_FAILURE() << "eval_s " << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find("wall.eval_s"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(code_of([&] { store.add_wall_time(run.id, second, "server-b"); }), ErrorCode::kAborted);
  store.set_state(run.id, RunState::kCancelled);
  EXPECT_EQ(code_of([&] { store.add_wall_time(run.id, second, "server-a"); }),
            ErrorCode::kFailedPrecondition);
  EXPECT_EQ(code_of([&] { store.add_wall_time(run.id, second); }), ErrorCode::kFailedPrecondition);
  EXPECT_EQ(store.get_run(run.id).wall, sum);
}

TEST_P(StoreContract, TheLatestCheckpointIsTheOneWithTheMostSteps) {
  auto s = open();
  Store& store = *s;
  const auto run = store.create_run(spec());
  const auto later = store.save_checkpoint(run.id, 3000, 0.5, kBlob);
  store.save_checkpoint(run.id, 1000, 0.5, kBlob);  // written after, fewer steps
  EXPECT_EQ(store.latest_checkpoint(run.id)->id, later.id);
  EXPECT_EQ(store.checkpoints(run.id).back().env_steps, 3000);
}

TEST_P(StoreContract, APromotionOfManyIsSeenWholeByAConcurrentReader) {
  auto w = open();
  Store& writer = *w;
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
  std::thread reader([&, store = open()] {
    while (!done) {
      std::set<std::int64_t> seen;
      for (const auto& p : store->promotions()) seen.insert(p.checkpoint_id);
      const bool whole = seen == std::set<std::int64_t>(sets[0].begin(), sets[0].end()) ||
                         seen == std::set<std::int64_t>(sets[1].begin(), sets[1].end());
      if (!whole) ++mixed;
      ++reads;
    }
  });
  for (int round = 0; round < 100; ++round)
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

// A client that retries a creation whose answer was lost (a dropped connection, a
// deadline) sends the same key: it gets the run the first call created, not a second.
TEST_P(StoreContract, ACreationRetriedWithItsKeyReturnsTheRunTheFirstCreated) {
  auto s = open();
  Store& store = *s;
  const RunRecord first = store.create_run(spec(), "key-1");
  const RunRecord retried = store.create_run(spec(), "key-1");
  EXPECT_EQ(retried.id, first.id);
  EXPECT_EQ(store.list_runs().size(), 1u);
  // Without a key, or with another, a run each time.
  EXPECT_NE(store.create_run(spec()).id, first.id);
  EXPECT_NE(store.create_run(spec(), "key-2").id, first.id);
  EXPECT_EQ(store.list_runs().size(), 3u);
  // The key of one run is never the answer for a different one.
  RunSpec other = spec();
  other.seed += 1;
  EXPECT_EQ(code_of([&] { store.create_run(other, "key-1"); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code_of([&] { store.create_run(spec(), std::string(600, 'k')); }),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(store.list_runs().size(), 3u);
}

TEST_P(StoreContract, AnImportIsOneTransactionOptionallyPromoted) {
  auto s = open();
  Store& store = *s;
  RunSpec finished = spec("retract");
  std::vector<FinishedRun> runs{{spec("approach"), {1, 2}}, {finished, {3}}};
  runs[1].spec.role = "nonsense";  // refused: nothing of the import is stored
  EXPECT_EQ(code_of([&] { store.import_finished(runs, true); }), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(store.list_runs().empty());
  EXPECT_TRUE(store.promotions().empty());
  runs[1].spec = finished;
  const auto ids = store.import_finished(runs, true);
  ASSERT_EQ(ids.size(), 2u);
  EXPECT_EQ(store.load_checkpoint(ids[1]).blob, std::vector<std::uint8_t>{3});
  EXPECT_EQ(store.promotions().size(), 2u);
  for (const auto& run : store.list_runs()) EXPECT_EQ(run.state, RunState::kSucceeded);
  EXPECT_EQ(store.import_finished(std::vector<FinishedRun>{{spec("hlc"), {9}}}, false).size(), 1u);
  EXPECT_EQ(store.promotions().size(), 2u);
}

TEST_P(StoreContract, RetentionKeepsTheLastBestPromotedAndReferencedCheckpoints) {
  auto s = open();
  Store& store = *s;
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

TEST_P(StoreContract, WeightsSavedBetweenEvaluationsKeepTheirCountersAndAreNeverTheBest) {
  auto s = open();
  Store& store = *s;
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

// A backup taken while a trainer keeps writing is one consistent snapshot, and it is a
// store: opening the copy is the restore.
TEST_P(StoreContract, ABackupTakenWhileATrainerWritesIsAWholeStoreThatOpensAsOne) {
  auto s = open();
  Store& store = *s;
  const auto served = store.create_run(spec("hlc"));
  const auto checkpoint = store.save_checkpoint(served.id, 100, 0.9, kBlob);
  store.promote(checkpoint.id, "ops");
  const auto training = store.create_run(spec());
  ASSERT_TRUE(store.claim_next("approach", "trainer", 60s));
  std::atomic<long long> written{0};
  std::jthread trainer([&, writer = open()](const std::stop_token& stop) {
    for (long long k = 1; !stop.stop_requested(); ++k) {
      writer->record_metric(training.id, {k * 100, k, 1.0, 0.5, 0.5, 0.5, 0, 0, k}, false, {},
                            "trainer");
      written = k;
    }
  });
  while (written < 20) std::this_thread::yield();
  const std::string copy = (dir_ / "backup.db").string();
  const BackupReport report = store.backup(copy);
  const long long at_least = written;
  trainer.request_stop();
  trainer.join();
  EXPECT_EQ(report.path, copy);
  EXPECT_EQ(report.runs, 2);
  EXPECT_EQ(report.checkpoints, 1);
  EXPECT_EQ(report.bytes, static_cast<std::int64_t>(std::filesystem::file_size(copy)));
  EXPECT_FALSE(std::filesystem::exists(copy + ".partial"));

  RunStore restored(copy);
  auto check = restored.database().prepare("PRAGMA integrity_check");
  ASSERT_TRUE(check.step());
  EXPECT_EQ(check.column_text(0), "ok");
  EXPECT_EQ(restored.promoted("hlc")->checkpoint_id, checkpoint.id);
  EXPECT_EQ(restored.promoted("hlc")->promoted_by, "ops");
  EXPECT_EQ(restored.load_checkpoint(checkpoint.id).blob, kBlob);
  // The curve in the copy is the live one up to some point: nothing torn, nothing invented.
  const auto copied = restored.metrics(training.id);
  const auto live = store.metrics(training.id);
  EXPECT_GE(static_cast<long long>(copied.size()), 1);
  EXPECT_LE(copied.size(), live.size());
  EXPECT_LE(static_cast<long long>(copied.size()), at_least + 1);
  for (std::size_t k = 0; k < copied.size(); ++k) EXPECT_EQ(copied[k].env_steps, live[k].env_steps);

  // A backup never overwrites a file.
  EXPECT_EQ(code_of([&] { store.backup(copy); }), ErrorCode::kFailedPrecondition);
  EXPECT_EQ(RunStore(copy).metrics(training.id).size(), copied.size());
}

INSTANTIATE_TEST_SUITE_P(Backends, StoreContract,
                         ::testing::Values(Backend::kEmbedded, Backend::kRemote), backend_name);

}  // namespace
}  // namespace pnp::store
