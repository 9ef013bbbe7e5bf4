#pragma once
// The platform's store: training runs, their learning curves, their checkpoints and the
// promoted checkpoint of each role, in one SQLite file. Every write is one transaction, so
// a crash never leaves half a checkpoint or a metric without its run; a checkpoint whose
// blob no longer matches its checksum is refused (DATA_LOSS), never returned; a commit is
// on disk when it returns (synchronous FULL).
//
// A run is trained by one owner at a time: a training server claims it with a lease it
// renews, and every write of a run's curve, checkpoints or state names its owner and is
// refused (ABORTED) if the run has another. Cancelling is the exception: any caller may
// cancel, and the owner finds out when it next renews or writes.
//
// A RunStore owns one connection: use one per thread (SQLite's WAL lets them read while
// another writes).

#include <chrono>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "store/records.h"
#include "store/sqlite.h"

namespace pnp::store {

struct RunFilter {
  std::optional<std::string> role;
  std::optional<RunState> state;
  int limit = 100;             // at most this many, newest first
  std::int64_t before_id = 0;  // > 0: only runs with a smaller id (paging)
};

// A finished run brought in from elsewhere with its one checkpoint (store/checkpoint_import.h).
struct FinishedRun {
  RunSpec spec;
  std::vector<std::uint8_t> blob;
};

// Which checkpoints retention keeps besides the last `keep_last` of each run: the run's
// best (highest evaluated success, the later one on a tie; unevaluated ones never), every promoted
// one, and every one another run starts from (parent or expert). Nothing else is kept.
struct RetentionPolicy {
  int keep_last = 3;
};

struct GcReport {
  std::int64_t checkpoints_deleted = 0;
  std::int64_t bytes_deleted = 0;  // checkpoint blob bytes
  std::int64_t pages_freed = 0;    // given back to the filesystem by the incremental vacuum
};

class RunStore {
 public:
  // Opens the database at `path` (read-write: creating and migrating it if needed;
  // read-only: it must exist with the current schema, and nothing is ever written).
  explicit RunStore(const std::string& path, const DatabaseOptions& options = {});

  RunRecord create_run(const RunSpec& spec);
  RunRecord get_run(std::int64_t id);  // NOT_FOUND if unknown
  std::vector<RunRecord> list_runs(const RunFilter& filter = {});
  // Moves a run to `state`. A finished run (succeeded, failed, cancelled) never changes
  // again: FAILED_PRECONDITION. Only the run's owner (`owner`; empty for an unowned run)
  // may move it, except to CANCELLED; a finished run has no owner.
  RunRecord set_state(std::int64_t id, RunState state, const std::string& error = "",
                      const std::string& owner = "");

  // Ownership. claim_next takes the oldest run of `role` that is pending, or running with
  // no owner or an expired lease (or already `owner`'s), sets it RUNNING and owned by
  // `owner` until now + lease, in one conditional update: two servers never both get it.
  std::optional<RunRecord> claim_next(const std::string& role, const std::string& owner,
                                      std::chrono::milliseconds lease);
  // Extends the lease; false if the run is no longer RUNNING and owned by `owner`
  // (cancelled, or taken over after the lease expired): its trainer must stop.
  bool renew_lease(std::int64_t run_id, const std::string& owner, std::chrono::milliseconds lease);
  // Gives the run up (still RUNNING, resumable): another server may take it at once.
  void release(std::int64_t run_id, const std::string& owner);
  // Runs of `role` claim_next would hand to `owner` now.
  std::int64_t count_claimable(const std::string& role, const std::string& owner);

  // Appends one evaluation of the learning curve and updates the run's summary, in one
  // transaction. An evaluation at the same step count replaces the earlier one (a
  // resumed run re-evaluates where it restarted). ABORTED unless `owner` owns the run.
  void record_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target, const std::string& owner = "");
  std::vector<MetricPoint> metrics(std::int64_t run_id);  // by env_steps
  // The points after `after_env_steps` only (a watcher's next page).
  std::vector<MetricPoint> metrics_after(std::int64_t run_id, long long after_env_steps);

  CheckpointInfo save_checkpoint(std::int64_t run_id, long long env_steps, double eval_success,
                                 std::span<const std::uint8_t> blob, const std::string& owner = "");
  // Weights saved between evaluations (a trainer stopped by a shutdown or a cancel) with
  // the counters it resumes from. Never counted as the run's best.
  CheckpointInfo save_unevaluated(std::int64_t run_id, long long env_steps,
                                  const TrainerCounters& counters,
                                  std::span<const std::uint8_t> blob,
                                  const std::string& owner = "");
  // An evaluation and the checkpoint it evaluated, in one transaction: a resumed run finds
  // its curve and its weights at the same step.
  CheckpointInfo record_evaluation(std::int64_t run_id, const MetricPoint& point,
                                   std::span<const std::uint8_t> blob, bool reached,
                                   std::optional<long long> steps_to_target,
                                   const std::string& owner = "");
  Checkpoint load_checkpoint(std::int64_t checkpoint_id);  // verified, or DATA_LOSS
  // The run's checkpoint with the most training steps (the latest id among equals).
  std::optional<CheckpointInfo> latest_checkpoint(std::int64_t run_id);
  std::vector<CheckpointInfo> checkpoints(std::int64_t run_id);  // by env_steps, then id
  CheckpointInfo checkpoint_info(std::int64_t checkpoint_id);    // no blob; NOT_FOUND if none

  // Finished runs with their checkpoints, all in one transaction (nothing is written if
  // any is refused), optionally promoted in the same transaction. Returns the checkpoint
  // ids in order.
  std::vector<std::int64_t> import_finished(std::span<const FinishedRun> runs, bool promote);

  // The checkpoints serve their roles from now on (replacing each role's previous one),
  // all in one transaction: a reader sees all of them or none. At most one per role.
  // `by`: the authorized principal that asked (empty without an auth policy).
  std::vector<Promotion> promote(std::span<const std::int64_t> checkpoint_ids,
                                 const std::string& by = "");
  Promotion promote(std::int64_t checkpoint_id, const std::string& by = "");
  std::optional<Promotion> promoted(const std::string& role);
  std::vector<Promotion> promotions();  // one consistent set

  // Deletes the checkpoints `policy` does not keep: of one run (after each evaluation) or
  // of every run; then gives free pages back to the filesystem.
  GcReport prune_checkpoints(std::int64_t run_id, const RetentionPolicy& policy);
  GcReport collect_garbage(const RetentionPolicy& policy);

  Database& database() { return db_; }

 private:
  void require_owner(const RunRecord& run, const std::string& owner, std::string_view action);
  void insert_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target, const std::string& owner);
  CheckpointInfo save_owned_checkpoint(std::int64_t run_id, long long env_steps,
                                       double eval_success, std::span<const std::uint8_t> blob,
                                       const std::string& owner,
                                       const TrainerCounters* unevaluated);
  // `unevaluated` null: an evaluated checkpoint (no counters of its own).
  std::int64_t insert_checkpoint(const RunRecord& run, long long env_steps, double eval_success,
                                 std::span<const std::uint8_t> blob,
                                 const TrainerCounters* unevaluated = nullptr);
  std::int64_t insert_run(const RunSpec& spec, RunState state);
  void upsert_promotion(const CheckpointInfo& info, Millis now, const std::string& by);
  GcReport prune_where(std::string_view run_condition, std::optional<std::int64_t> run_id,
                       const RetentionPolicy& policy);
  Database db_;
};

Millis now_ms();

}  // namespace pnp::store
