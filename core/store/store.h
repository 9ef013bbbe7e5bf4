#pragma once
// The platform's store, as every server sees it: training runs, their learning curves,
// their checkpoints and the promoted checkpoint of each role. Two implementations keep
// the same contract (tests/store_contract/store_contract.h runs one suite against both):
//   RunStore      the SQLite file in this process (store/run_store.h), for one machine;
//   RemoteStore   a client of pnp-store-server, the one process that opens the file
//                 (services/store/remote_store.h), for servers on other machines.
//
// Every write is one transaction, so a crash never leaves half a checkpoint or a metric
// without its run; a checkpoint whose blob no longer matches its checksum is refused
// (DATA_LOSS), never returned.
//
// A run is trained by one owner at a time: a training server claims it with a lease it
// renews, and every write of a run's curve, checkpoints or state names its owner and is
// refused (ABORTED) if the run has another. Cancelling is the exception: any caller may
// cancel, and the owner finds out when it next renews or writes.
//
// One Store object is used by one thread at a time (open one per thread).

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "store/backup.h"
#include "store/records.h"

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
  // Instead of `blob`: reads it when it is stored, so that an import of several large
  // checkpoints holds one at a time (the store server's imports are spooled to disk).
  std::function<std::vector<std::uint8_t>()> read_blob{};

  // The checkpoint's bytes: `blob`, or what read_blob reads into `scratch`.
  const std::vector<std::uint8_t>& bytes(std::vector<std::uint8_t>& scratch) const {
    if (!read_blob) return blob;
    scratch = read_blob();
    return scratch;
  }
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

class Store {
 public:
  virtual ~Store() = default;
  Store() = default;
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;
  Store(Store&&) = default;
  Store& operator=(Store&&) = default;

  // A new pending run. `request_id` non-empty makes it idempotent: a run already created
  // with that key is returned instead of a second (a retried call whose answer was lost);
  // the key for another spec is INVALID_ARGUMENT. At most kMaxRequestIdBytes.
  virtual RunRecord create_run(const RunSpec& spec, const std::string& request_id = "") = 0;
  virtual RunRecord get_run(std::int64_t id) = 0;  // NOT_FOUND if unknown
  virtual std::vector<RunRecord> list_runs(const RunFilter& filter = {}) = 0;
  // Moves a run to `state`. A finished run (succeeded, failed, cancelled) never changes
  // again: FAILED_PRECONDITION. Only the run's owner (`owner`; empty for an unowned run)
  // may move it, except to CANCELLED; a finished run has no owner.
  virtual RunRecord set_state(std::int64_t id, RunState state, const std::string& error = "",
                              const std::string& owner = "") = 0;

  // Ownership. claim_next takes the oldest run of `role` that is pending, or running with
  // no owner or an expired lease (or already `owner`'s), sets it RUNNING and owned by
  // `owner` until now + lease, in one conditional update: two servers never both get it.
  virtual std::optional<RunRecord> claim_next(const std::string& role, const std::string& owner,
                                              std::chrono::milliseconds lease) = 0;
  // Extends the lease; false if the run is no longer RUNNING and owned by `owner`
  // (cancelled, or taken over after the lease expired): its trainer must stop.
  virtual bool renew_lease(std::int64_t run_id, const std::string& owner,
                           std::chrono::milliseconds lease) = 0;
  // Adds one trainer's part of the run's wall time, by phase, to the run's sums (a resumed
  // run is trained in parts), as the trainer stops: finished, cancelled or shut down (a
  // trainer that failed records none). Every phase in [0, kMaxWallPartSeconds] (INVALID_ARGUMENT
  // naming it); FAILED_PRECONDITION for a finished run (its sums are final: a run cancelled while
  // training keeps those of its earlier parts); ABORTED unless `owner` owns the run.
  virtual RunRecord add_wall_time(std::int64_t run_id, const WallBreakdown& part,
                                  const std::string& owner = "") = 0;
  // Gives the run up (still RUNNING, resumable): another server may take it at once.
  virtual void release(std::int64_t run_id, const std::string& owner) = 0;
  // Runs of `role` claim_next would hand to `owner` now.
  virtual std::int64_t count_claimable(const std::string& role, const std::string& owner) = 0;

  // Appends one evaluation of the learning curve and updates the run's summary, in one
  // transaction. An evaluation at the same step count replaces the earlier one (a
  // resumed run re-evaluates where it restarted). ABORTED unless `owner` owns the run.
  virtual void record_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                             std::optional<long long> steps_to_target,
                             const std::string& owner = "") = 0;
  virtual std::vector<MetricPoint> metrics(std::int64_t run_id) = 0;  // by env_steps
  // The points after `after_env_steps` only (a watcher's next page).
  virtual std::vector<MetricPoint> metrics_after(std::int64_t run_id,
                                                 long long after_env_steps) = 0;

  virtual CheckpointInfo save_checkpoint(std::int64_t run_id, long long env_steps,
                                         double eval_success, std::span<const std::uint8_t> blob,
                                         const std::string& owner = "") = 0;
  // Weights saved between evaluations (a trainer stopped by a shutdown or a cancel) with
  // the counters it resumes from. Never counted as the run's best.
  virtual CheckpointInfo save_unevaluated(std::int64_t run_id, long long env_steps,
                                          const TrainerCounters& counters,
                                          std::span<const std::uint8_t> blob,
                                          const std::string& owner = "") = 0;
  // An evaluation and the checkpoint it evaluated, in one transaction: a resumed run finds
  // its curve and its weights at the same step.
  virtual CheckpointInfo record_evaluation(std::int64_t run_id, const MetricPoint& point,
                                           std::span<const std::uint8_t> blob, bool reached,
                                           std::optional<long long> steps_to_target,
                                           const std::string& owner = "") = 0;
  virtual Checkpoint load_checkpoint(std::int64_t checkpoint_id) = 0;  // verified, or DATA_LOSS
  // The run's checkpoint with the most training steps (the latest id among equals).
  virtual std::optional<CheckpointInfo> latest_checkpoint(std::int64_t run_id) = 0;
  virtual std::vector<CheckpointInfo> checkpoints(std::int64_t run_id) = 0;  // by env_steps, id
  virtual CheckpointInfo checkpoint_info(std::int64_t checkpoint_id) = 0;    // NOT_FOUND if none

  // Finished runs with their checkpoints, all in one transaction (nothing is written if
  // any is refused), optionally promoted in the same transaction (`by` as promote's; a
  // remote store records the caller it authenticated instead). Returns the checkpoint ids
  // in order.
  virtual std::vector<std::int64_t> import_finished(std::span<const FinishedRun> runs, bool promote,
                                                    const std::string& by = "") = 0;

  // The checkpoints serve their roles from now on (replacing each role's previous one),
  // all in one transaction: a reader sees all of them or none. At most one per role.
  // `by`: the authorized principal that asked (empty without an auth policy; a remote store
  // records the caller it authenticated, or the operator a delegate server names).
  virtual std::vector<Promotion> promote(std::span<const std::int64_t> checkpoint_ids,
                                         const std::string& by = "") = 0;
  Promotion promote(std::int64_t checkpoint_id, const std::string& by = "");
  virtual std::optional<Promotion> promoted(const std::string& role) = 0;
  virtual std::vector<Promotion> promotions() = 0;  // one consistent set

  // Deletes the checkpoints `policy` does not keep: of one run (after each evaluation) or
  // of every run; then gives free pages back to the filesystem.
  virtual GcReport prune_checkpoints(std::int64_t run_id, const RetentionPolicy& policy) = 0;
  virtual GcReport collect_garbage(const RetentionPolicy& policy) = 0;

  // A consistent copy of the whole store into the new local file `destination`, taken
  // while others keep writing (store/backup.h); the copy is itself a store file.
  virtual BackupReport backup(const std::string& destination) = 0;
};

// How a component opens its own handle on the store (one per thread): a RunStore on a path,
// or a RemoteStore on a channel.
using StoreOpener = std::function<std::unique_ptr<Store>()>;

}  // namespace pnp::store
