#pragma once
// The store in one SQLite file, in this process (the contract is store/store.h's). A
// commit is on disk when it returns (synchronous FULL). A RunStore owns one connection:
// use one per thread (SQLite's WAL lets them read while another writes).

#include <chrono>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "store/records.h"
#include "store/sqlite.h"
#include "store/store.h"
#include "store/store_quotas.h"

namespace pnp::store {

class RunStore final : public Store {
 public:
  // Opens the database at `path` (read-write: creating and migrating it if needed;
  // read-only: it must exist with the current schema, and nothing is ever written).
  explicit RunStore(const std::string& path, const DatabaseOptions& options = {},
                    const StoreQuotas& quotas = {});

  RunRecord create_run(const RunSpec& spec, const std::string& request_id = "") override;
  // As create_run, for the authenticated principal `created_by` (empty: none), who may
  // hold at most quotas.max_open_runs_per_principal pending or running runs.
  RunRecord create_run_for(const RunSpec& spec, const std::string& request_id,
                           const std::string& created_by);
  RunRecord get_run(std::int64_t id) override;
  std::vector<RunRecord> list_runs(const RunFilter& filter = {}) override;
  RunRecord set_state(std::int64_t id, RunState state, const std::string& error = "",
                      const std::string& owner = "") override;

  std::optional<RunRecord> claim_next(const std::string& role, const std::string& owner,
                                      std::chrono::milliseconds lease) override;
  bool renew_lease(std::int64_t run_id, const std::string& owner,
                   std::chrono::milliseconds lease) override;
  RunRecord add_wall_time(std::int64_t run_id, const WallBreakdown& part,
                          const std::string& owner = "") override;
  void release(std::int64_t run_id, const std::string& owner) override;
  std::int64_t count_claimable(const std::string& role, const std::string& owner) override;

  void record_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target,
                     const std::string& owner = "") override;
  std::vector<MetricPoint> metrics(std::int64_t run_id) override;
  std::vector<MetricPoint> metrics_after(std::int64_t run_id, long long after_env_steps) override;

  CheckpointInfo save_checkpoint(std::int64_t run_id, long long env_steps, double eval_success,
                                 std::span<const std::uint8_t> blob,
                                 const std::string& owner = "") override;
  CheckpointInfo save_unevaluated(std::int64_t run_id, long long env_steps,
                                  const TrainerCounters& counters,
                                  std::span<const std::uint8_t> blob,
                                  const std::string& owner = "") override;
  CheckpointInfo record_evaluation(std::int64_t run_id, const MetricPoint& point,
                                   std::span<const std::uint8_t> blob, bool reached,
                                   std::optional<long long> steps_to_target,
                                   const std::string& owner = "") override;
  Checkpoint load_checkpoint(std::int64_t checkpoint_id) override;
  std::optional<CheckpointInfo> latest_checkpoint(std::int64_t run_id) override;
  std::vector<CheckpointInfo> checkpoints(std::int64_t run_id) override;
  CheckpointInfo checkpoint_info(std::int64_t checkpoint_id) override;

  std::vector<std::int64_t> import_finished(std::span<const FinishedRun> runs, bool promote,
                                            const std::string& by = "") override;

  using Store::promote;
  std::vector<Promotion> promote(std::span<const std::int64_t> checkpoint_ids,
                                 const std::string& by = "") override;
  std::optional<Promotion> promoted(const std::string& role) override;
  std::vector<Promotion> promotions() override;

  GcReport prune_checkpoints(std::int64_t run_id, const RetentionPolicy& policy) override;
  GcReport collect_garbage(const RetentionPolicy& policy) override;
  BackupReport backup(const std::string& destination) override;

  Database& database() { return db_; }

 private:
  void require_owner(const RunRecord& run, const std::string& owner, std::string_view action);
  // FAILED_PRECONDITION for a finished run, else as require_owner.
  void require_open_and_owned(std::int64_t run_id, const std::string& owner,
                              std::string_view action);
  void insert_metric(std::int64_t run_id, const MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target, const std::string& owner);
  CheckpointInfo save_owned_checkpoint(std::int64_t run_id, long long env_steps,
                                       double eval_success, std::span<const std::uint8_t> blob,
                                       const std::string& owner,
                                       const TrainerCounters* unevaluated);
  // `unevaluated` null: an evaluated checkpoint (no counters of its own).
  // RESOURCE_EXHAUSTED past the quotas (store_quotas.h).
  void require_open_run_quota(const std::string& created_by);
  void require_checkpoint_quota(const RunRecord& run, std::size_t bytes);
  std::int64_t insert_checkpoint(const RunRecord& run, long long env_steps, double eval_success,
                                 std::span<const std::uint8_t> blob,
                                 const TrainerCounters* unevaluated = nullptr);
  std::int64_t insert_run(const RunSpec& spec, RunState state);
  void upsert_promotion(const CheckpointInfo& info, Millis now, const std::string& by);
  GcReport prune_where(std::string_view run_condition, std::optional<std::int64_t> run_id,
                       const RetentionPolicy& policy);
  Database db_;
  StoreQuotas quotas_;
};

Millis now_ms();

}  // namespace pnp::store
