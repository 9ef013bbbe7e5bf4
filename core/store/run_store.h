#pragma once
// The platform's store: training runs, their learning curves, their checkpoints and the
// promoted checkpoint of each role, in one SQLite file. Every write is one transaction, so
// a crash never leaves half a checkpoint or a metric without its run; a checkpoint whose
// blob no longer matches its checksum is refused (DATA_LOSS), never returned.
//
// A RunStore owns one connection: use one per thread (SQLite's WAL lets them read while
// another writes).

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

class RunStore {
 public:
  // Opens (creating if needed) and migrates the database at `path`.
  explicit RunStore(const std::string& path);

  RunRecord create_run(const RunSpec& spec);
  RunRecord get_run(std::int64_t id);  // NOT_FOUND if unknown
  std::vector<RunRecord> list_runs(const RunFilter& filter = {});
  // Moves a run to `state`. A finished run (succeeded, failed, cancelled) never changes
  // again: FAILED_PRECONDITION.
  RunRecord set_state(std::int64_t id, RunState state, const std::string& error = "");

  // Appends one evaluation of the learning curve and updates the run's summary, in one
  // transaction. An evaluation at the same step count replaces the earlier one (a
  // resumed run re-evaluates where it restarted).
  void record_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target);
  std::vector<MetricPoint> metrics(std::int64_t run_id);  // by env_steps

  CheckpointInfo save_checkpoint(std::int64_t run_id, long long env_steps, double eval_success,
                                 std::span<const std::uint8_t> blob);
  // An evaluation and the checkpoint it evaluated, in one transaction: a resumed run finds
  // its curve and its weights at the same step.
  CheckpointInfo record_evaluation(std::int64_t run_id, const MetricPoint& point,
                                   std::span<const std::uint8_t> blob, bool reached,
                                   std::optional<long long> steps_to_target);
  Checkpoint load_checkpoint(std::int64_t checkpoint_id);  // verified, or DATA_LOSS
  std::optional<CheckpointInfo> latest_checkpoint(std::int64_t run_id);
  std::vector<CheckpointInfo> checkpoints(std::int64_t run_id);
  CheckpointInfo checkpoint_info(std::int64_t checkpoint_id);  // no blob; NOT_FOUND if none

  // The checkpoint serves its role from now on (replacing the role's previous one).
  Promotion promote(std::int64_t checkpoint_id);
  std::optional<Promotion> promoted(const std::string& role);
  std::vector<Promotion> promotions();

  Database& database() { return db_; }

 private:
  void insert_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target);
  std::int64_t insert_checkpoint(std::int64_t run_id, long long env_steps, double eval_success,
                                 std::span<const std::uint8_t> blob);
  Database db_;
};

Millis now_ms();

}  // namespace pnp::store
