#include "store/run_store.h"

#include <chrono>
#include <cmath>
#include <utility>

#include "common/checksum.h"
#include "common/error.h"
#include "store/backup.h"
#include "store/schema.h"

namespace pnp::store {
namespace {

constexpr const char* kRunColumns =
    "id, role, algorithm, robot, object, seed, config_json, code_commit, parent_checkpoint_id, "
    "state, error, env_steps, last_success, reached, steps_to_target, created_ms, updated_ms, "
    "finished_ms, gemm_path, last_score, owner, lease_expires_ms, wall_rollout_s, wall_update_s, "
    "wall_eval_s, wall_report_s, wall_other_s";

RunRecord read_run(const Statement& st) {
  RunRecord r;
  r.id = st.column_int(0);
  r.spec.role = st.column_text(1);
  r.spec.algorithm = st.column_text(2);
  r.spec.robot = st.column_text(3);
  r.spec.object = st.column_text(4);
  r.spec.seed = static_cast<std::uint64_t>(st.column_int(5));
  r.spec.config_json = st.column_text(6);
  r.spec.code_commit = st.column_text(7);
  if (!st.is_null(8)) r.spec.parent_checkpoint_id = st.column_int(8);
  r.state = parse_run_state(st.column_text(9), "runs.state");
  r.error = st.column_text(10);
  r.env_steps = st.column_int(11);
  r.last_success = st.column_double(12);
  r.reached = st.column_int(13) != 0;
  if (!st.is_null(14)) r.steps_to_target = st.column_int(14);
  r.created_ms = st.column_int(15);
  r.updated_ms = st.column_int(16);
  if (!st.is_null(17)) r.finished_ms = st.column_int(17);
  r.spec.gemm_path = st.column_text(18);
  if (!st.is_null(19)) r.last_score = st.column_double(19);
  r.owner = st.column_text(20);
  if (!st.is_null(21)) r.lease_expires_ms = st.column_int(21);
  WallBreakdown& w = r.wall;
  w.rollout_s = st.column_double(22);
  w.update_s = st.column_double(23);
  w.eval_s = st.column_double(24);
  w.report_s = st.column_double(25);
  w.other_s = st.column_double(26);
  w.total_s = w.phases_sum();
  return r;
}

constexpr const char* kCheckpointColumns =
    "id, run_id, role, env_steps, eval_success, checksum, size_bytes, created_ms, episodes, "
    "updates, wall_s, eval_wall_s";

CheckpointInfo read_checkpoint_info(const Statement& st) {
  CheckpointInfo c;
  c.id = st.column_int(0);
  c.run_id = st.column_int(1);
  c.role = st.column_text(2);
  c.env_steps = st.column_int(3);
  c.eval_success = st.column_double(4);
  c.checksum = st.column_text(5);
  c.size_bytes = st.column_int(6);
  c.created_ms = st.column_int(7);
  if (!st.is_null(8)) {
    c.unevaluated = TrainerCounters{st.column_int(8), st.column_int(9), st.column_double(10),
                                    st.column_double(11)};
  }
  return c;
}

void require_spec(const RunSpec& spec) {
  if (!is_known_role(spec.role))
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + spec.role + "\"");
  if (spec.algorithm.empty()) throw_invalid_argument("algorithm", "a name", "an empty string");
  if (spec.robot.empty()) throw_invalid_argument("robot", "a name", "an empty string");
  if (spec.object.empty()) throw_invalid_argument("object", "a name", "an empty string");
}

}  // namespace

Millis now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

RunStore::RunStore(const std::string& path, const DatabaseOptions& options,
                   const StoreQuotas& quotas)
    : db_(path, options), quotas_(quotas) {
  migrate(db_);
}

RunRecord RunStore::create_run(const RunSpec& spec, const std::string& request_id) {
  return create_run_for(spec, request_id, "");
}

RunRecord RunStore::create_run_for(const RunSpec& spec, const std::string& request_id,
                                   const std::string& created_by) {
  require_spec(spec);
  if (request_id.size() > kMaxRequestIdBytes) {
    throw_invalid_argument("request_id", "at most " + std::to_string(kMaxRequestIdBytes) + " bytes",
                           std::to_string(request_id.size()) + " bytes");
  }
  Transaction tx(db_);
  if (!request_id.empty()) {
    auto find = db_.prepare("SELECT id FROM runs WHERE request_id = ?");
    find.bind(1, request_id);
    if (find.step()) {
      RunRecord existing = get_run(find.column_int(0));
      const RunSpec& was = existing.spec;
      if (was.role != spec.role || was.algorithm != spec.algorithm || was.robot != spec.robot ||
          was.object != spec.object || was.seed != spec.seed ||
          was.config_json != spec.config_json ||
          was.parent_checkpoint_id != spec.parent_checkpoint_id) {
        throw_invalid_argument("request_id", "a new key for a different run",
                               "the key of run " + std::to_string(existing.id));
      }
      return existing;  // the retried call's run
    }
  }
  if (spec.parent_checkpoint_id) checkpoint_info(*spec.parent_checkpoint_id);  // NOT_FOUND
  if (!created_by.empty()) require_open_run_quota(created_by);
  const std::int64_t id = insert_run(spec, RunState::kPending);
  auto tag = db_.prepare("UPDATE runs SET request_id = ?, created_by = ? WHERE id = ?");
  if (request_id.empty())
    tag.bind_null(1);
  else
    tag.bind(1, request_id);
  tag.bind(2, created_by).bind(3, id);
  tag.run();
  tx.commit();
  return get_run(id);
}

std::int64_t RunStore::insert_run(const RunSpec& spec, RunState state) {
  const Millis now = now_ms();
  auto st = db_.prepare(
      "INSERT INTO runs (role, algorithm, robot, object, seed, config_json, code_commit, "
      "parent_checkpoint_id, state, created_ms, updated_ms, gemm_path, finished_ms) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  st.bind(1, spec.role)
      .bind(2, spec.algorithm)
      .bind(3, spec.robot)
      .bind(4, spec.object)
      .bind(5, static_cast<std::int64_t>(spec.seed))
      .bind(6, spec.config_json)
      .bind(7, spec.code_commit)
      .bind_optional(8, spec.parent_checkpoint_id)
      .bind(9, run_state_name(state))
      .bind(10, now)
      .bind(11, now)
      .bind(12, spec.gemm_path)
      .bind_optional(13, is_terminal(state) ? std::optional<std::int64_t>(now) : std::nullopt);
  st.run();
  return db_.last_insert_id();
}

RunRecord RunStore::get_run(std::int64_t id) {
  auto st = db_.prepare(std::string("SELECT ") + kRunColumns + " FROM runs WHERE id = ?");
  st.bind(1, id);
  if (!st.step()) {
    throw Error(ErrorCode::kNotFound,
                "run " + std::to_string(id) + " not found in store " + db_.path());
  }
  return read_run(st);
}

std::vector<RunRecord> RunStore::list_runs(const RunFilter& filter) {
  if (filter.limit <= 0)
    throw_invalid_argument("limit", "a positive number", std::to_string(filter.limit));
  if (filter.role && !is_known_role(*filter.role))
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + *filter.role + "\"");
  auto st = db_.prepare(std::string("SELECT ") + kRunColumns +
                        " FROM runs WHERE (?1 IS NULL OR role = ?1) AND (?2 IS NULL OR state = ?2)"
                        " AND (?3 = 0 OR id < ?3) ORDER BY id DESC LIMIT ?4");
  if (filter.role) st.bind(1, *filter.role);
  if (filter.state) st.bind(2, run_state_name(*filter.state));
  st.bind(3, filter.before_id).bind(4, static_cast<std::int64_t>(filter.limit));
  std::vector<RunRecord> out;
  while (st.step()) out.push_back(read_run(st));
  return out;
}

RunRecord RunStore::set_state(std::int64_t id, RunState state, const std::string& error,
                              const std::string& owner) {
  Transaction tx(db_);
  const RunRecord current = get_run(id);
  if (is_terminal(current.state) && current.state != state) {
    throw Error(ErrorCode::kFailedPrecondition, "run " + std::to_string(id) + " is already " +
                                                    std::string(run_state_name(current.state)) +
                                                    "; it cannot become " +
                                                    std::string(run_state_name(state)));
  }
  if (state != RunState::kCancelled) require_owner(current, owner, "change its state");
  const Millis now = now_ms();
  const bool terminal = is_terminal(state);
  auto st = db_.prepare(
      "UPDATE runs SET state = ?1, error = ?2, updated_ms = ?3, "
      "finished_ms = CASE WHEN ?4 THEN COALESCE(finished_ms, ?3) ELSE NULL END, "
      "owner = CASE WHEN ?4 THEN NULL ELSE owner END, "
      "lease_expires_ms = CASE WHEN ?4 THEN NULL ELSE lease_expires_ms END WHERE id = ?5");
  st.bind(1, run_state_name(state))
      .bind(2, error)
      .bind(3, now)
      .bind(4, static_cast<std::int64_t>(terminal))
      .bind(5, id);
  st.run();
  tx.commit();
  return get_run(id);
}

void RunStore::require_open_and_owned(std::int64_t run_id, const std::string& owner,
                                      std::string_view action) {
  const RunRecord run = get_run(run_id);
  if (is_terminal(run.state)) {
    throw Error(ErrorCode::kFailedPrecondition,
                "run " + std::to_string(run_id) + " is " + std::string(run_state_name(run.state)) +
                    ": a finished run cannot " + std::string(action));
  }
  require_owner(run, owner, action);
}

void RunStore::require_owner(const RunRecord& run, const std::string& owner,
                             std::string_view action) {
  if (run.owner == owner) return;
  throw Error(ErrorCode::kAborted,
              "run " + std::to_string(run.id) + " is " +
                  (run.owner.empty() ? std::string("held by no training server")
                                     : "held by training server " + run.owner) +
                  ", not by " + (owner.empty() ? std::string("this caller") : owner) +
                  ": it cannot " + std::string(action));
}

namespace {

// Pending, or running without a live owner (or with `?2` as its owner), at time `?3`.
constexpr const char* kClaimable =
    "role = ?1 AND (state = 'pending' OR (state = 'running' AND (owner IS NULL OR owner = ?2 "
    "OR lease_expires_ms IS NULL OR lease_expires_ms < ?3)))";

}  // namespace

std::optional<RunRecord> RunStore::claim_next(const std::string& role, const std::string& owner,
                                              std::chrono::milliseconds lease) {
  if (owner.empty()) throw_invalid_argument("owner", "a training server's name", "\"\"");
  Transaction tx(db_);
  const Millis now = now_ms();
  auto pick =
      db_.prepare(std::string("SELECT id FROM runs WHERE ") + kClaimable + " ORDER BY id LIMIT 1");
  pick.bind(1, role).bind(2, owner).bind(3, now);
  if (!pick.step()) return std::nullopt;
  const std::int64_t id = pick.column_int(0);
  auto claim = db_.prepare(
      "UPDATE runs SET state = 'running', owner = ?, lease_expires_ms = ?, updated_ms = ? "
      "WHERE id = ?");
  claim.bind(1, owner).bind(2, now + lease.count()).bind(3, now).bind(4, id);
  claim.run();
  tx.commit();
  return get_run(id);
}

bool RunStore::renew_lease(std::int64_t run_id, const std::string& owner,
                           std::chrono::milliseconds lease) {
  auto st = db_.prepare(
      "UPDATE runs SET lease_expires_ms = ? WHERE id = ? AND owner = ? AND state = 'running'");
  st.bind(1, now_ms() + lease.count()).bind(2, run_id).bind(3, owner);
  st.run();
  return db_.changes() == 1;
}

RunRecord RunStore::add_wall_time(std::int64_t run_id, const WallBreakdown& part,
                                  const std::string& owner) {
  const std::pair<const char*, double> phases[] = {{"wall.rollout_s", part.rollout_s},
                                                   {"wall.update_s", part.update_s},
                                                   {"wall.eval_s", part.eval_s},
                                                   {"wall.report_s", part.report_s},
                                                   {"wall.other_s", part.other_s}};
  for (const auto& [field, seconds] : phases) {
    if (!std::isfinite(seconds) || seconds < 0 || seconds > kMaxWallPartSeconds) {
      throw_invalid_argument(
          field,
          "seconds in [0, " + std::to_string(static_cast<long long>(kMaxWallPartSeconds)) + "]",
          std::to_string(seconds));
    }
  }
  Transaction tx(db_);
  require_open_and_owned(run_id, owner, "record wall time");
  auto st = db_.prepare(
      "UPDATE runs SET wall_rollout_s = wall_rollout_s + ?, wall_update_s = wall_update_s + ?, "
      "wall_eval_s = wall_eval_s + ?, wall_report_s = wall_report_s + ?, "
      "wall_other_s = wall_other_s + ? WHERE id = ?");
  st.bind(1, part.rollout_s)
      .bind(2, part.update_s)
      .bind(3, part.eval_s)
      .bind(4, part.report_s)
      .bind(5, part.other_s)
      .bind(6, run_id);
  st.run();
  tx.commit();
  return get_run(run_id);
}

void RunStore::release(std::int64_t run_id, const std::string& owner) {
  auto st = db_.prepare(
      "UPDATE runs SET owner = NULL, lease_expires_ms = NULL WHERE id = ? AND owner = ?");
  st.bind(1, run_id).bind(2, owner);
  st.run();
}

std::int64_t RunStore::count_claimable(const std::string& role, const std::string& owner) {
  auto st = db_.prepare(std::string("SELECT COUNT(*) FROM runs WHERE ") + kClaimable);
  st.bind(1, role).bind(2, owner).bind(3, now_ms());
  st.step();
  return st.column_int(0);
}

void RunStore::record_metric(std::int64_t run_id, const MetricPoint& p, bool reached,
                             std::optional<long long> steps_to_target, const std::string& owner) {
  Transaction tx(db_);
  insert_metric(run_id, p, reached, steps_to_target, owner);
  tx.commit();
}

CheckpointInfo RunStore::record_evaluation(std::int64_t run_id, const MetricPoint& point,
                                           std::span<const std::uint8_t> blob, bool reached,
                                           std::optional<long long> steps_to_target,
                                           const std::string& owner) {
  if (blob.empty()) throw_invalid_argument("checkpoint", "a non-empty blob", "0 bytes");
  Transaction tx(db_);
  insert_metric(run_id, point, reached, steps_to_target, owner);
  const std::int64_t id =
      insert_checkpoint(get_run(run_id), point.env_steps, point.task_success, blob);
  tx.commit();
  return checkpoint_info(id);
}

void RunStore::insert_metric(std::int64_t run_id, const MetricPoint& p, bool reached,
                             std::optional<long long> steps_to_target, const std::string& owner) {
  require_open_and_owned(run_id, owner, "take metrics");
  auto insert = db_.prepare(
      "INSERT OR REPLACE INTO metrics (run_id, env_steps, episodes, wall_s, task_success, "
      "subtask_success, sampled_success, critic_loss, actor_loss, updates, stop_score) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  insert.bind(1, run_id)
      .bind(2, static_cast<std::int64_t>(p.env_steps))
      .bind(3, static_cast<std::int64_t>(p.episodes))
      .bind(4, p.wall_s)
      .bind(5, p.task_success)
      .bind(6, p.subtask_success)
      .bind(7, p.sampled_success)
      .bind(8, p.critic_loss)
      .bind(9, p.actor_loss)
      .bind(10, static_cast<std::int64_t>(p.updates))
      .bind_optional(11, p.stop_score);
  insert.run();
  auto update = db_.prepare(
      "UPDATE runs SET env_steps = ?, last_success = ?, reached = ?, steps_to_target = ?, "
      "updated_ms = ?, last_score = ? WHERE id = ?");
  update.bind(1, static_cast<std::int64_t>(p.env_steps))
      .bind(2, p.task_success)
      .bind(3, static_cast<std::int64_t>(reached))
      .bind_optional(4,
                     steps_to_target ? std::optional<std::int64_t>(*steps_to_target) : std::nullopt)
      .bind(5, now_ms())
      .bind_optional(6, p.stop_score)
      .bind(7, run_id);
  update.run();
}

namespace {

std::vector<MetricPoint> read_metrics(Statement& st) {
  std::vector<MetricPoint> out;
  while (st.step()) {
    MetricPoint& p =
        out.emplace_back(MetricPoint{st.column_int(0), st.column_int(1), st.column_double(2),
                                     st.column_double(3), st.column_double(4), st.column_double(5),
                                     st.column_double(6), st.column_double(7), st.column_int(8)});
    if (!st.is_null(9)) p.stop_score = st.column_double(9);
  }
  return out;
}

constexpr const char* kMetricColumns =
    "SELECT env_steps, episodes, wall_s, task_success, subtask_success, sampled_success, "
    "critic_loss, actor_loss, updates, stop_score FROM metrics ";

}  // namespace

std::vector<MetricPoint> RunStore::metrics(std::int64_t run_id) {
  get_run(run_id);  // NOT_FOUND for an unknown run, rather than an empty curve
  auto st = db_.prepare(std::string(kMetricColumns) + "WHERE run_id = ? ORDER BY env_steps");
  st.bind(1, run_id);
  return read_metrics(st);
}

std::vector<MetricPoint> RunStore::metrics_after(std::int64_t run_id, long long after_env_steps) {
  get_run(run_id);
  auto st = db_.prepare(std::string(kMetricColumns) +
                        "WHERE run_id = ? AND env_steps > ? ORDER BY env_steps");
  st.bind(1, run_id).bind(2, static_cast<std::int64_t>(after_env_steps));
  return read_metrics(st);
}

CheckpointInfo RunStore::save_checkpoint(std::int64_t run_id, long long env_steps,
                                         double eval_success, std::span<const std::uint8_t> blob,
                                         const std::string& owner) {
  return save_owned_checkpoint(run_id, env_steps, eval_success, blob, owner, nullptr);
}

CheckpointInfo RunStore::save_unevaluated(std::int64_t run_id, long long env_steps,
                                          const TrainerCounters& counters,
                                          std::span<const std::uint8_t> blob,
                                          const std::string& owner) {
  if (counters.episodes < 0 || counters.updates < 0 || !(counters.wall_s >= 0) ||
      !(counters.eval_wall_s >= 0)) {
    throw_invalid_argument("counters", "non-negative episodes, updates and times",
                           std::to_string(counters.episodes) + " episodes, " +
                               std::to_string(counters.updates) + " updates");
  }
  return save_owned_checkpoint(run_id, env_steps, 0, blob, owner, &counters);
}

CheckpointInfo RunStore::save_owned_checkpoint(std::int64_t run_id, long long env_steps,
                                               double eval_success,
                                               std::span<const std::uint8_t> blob,
                                               const std::string& owner,
                                               const TrainerCounters* unevaluated) {
  if (blob.empty()) throw_invalid_argument("checkpoint", "a non-empty blob", "0 bytes");
  Transaction tx(db_);
  const RunRecord run = get_run(run_id);
  require_owner(run, owner, "take checkpoints");
  const std::int64_t id = insert_checkpoint(run, env_steps, eval_success, blob, unevaluated);
  tx.commit();
  return checkpoint_info(id);
}

void RunStore::require_open_run_quota(const std::string& created_by) {
  auto open = db_.prepare(
      "SELECT COUNT(*) FROM runs WHERE created_by = ? AND state IN ('pending', 'running')");
  open.bind(1, created_by);
  open.step();
  if (open.column_int(0) >= quotas_.max_open_runs_per_principal) {
    throw Error(ErrorCode::kResourceExhausted,
                "spec: \"" + created_by + "\" already has " + std::to_string(open.column_int(0)) +
                    " pending or running runs, its quota (--max-open-runs-per-principal " +
                    std::to_string(quotas_.max_open_runs_per_principal) +
                    "): wait for some to finish or cancel them");
  }
}

void RunStore::require_checkpoint_quota(const RunRecord& run, std::size_t bytes) {
  const auto size = static_cast<std::int64_t>(bytes);
  if (size > quotas_.max_checkpoint_bytes) {
    throw Error(ErrorCode::kResourceExhausted,
                "checkpoint: " + std::to_string(size) + " bytes, more than the " +
                    std::to_string(quotas_.max_checkpoint_bytes) +
                    " one checkpoint may have (--max-checkpoint-mb)");
  }
  auto used = db_.prepare("SELECT COALESCE(SUM(size_bytes), 0) FROM checkpoints WHERE run_id = ?");
  used.bind(1, run.id);
  used.step();
  const std::int64_t held = used.column_int(0);
  if (held + size > quotas_.max_run_checkpoint_bytes) {
    throw Error(ErrorCode::kResourceExhausted,
                "checkpoint: run " + std::to_string(run.id) + " already holds " +
                    std::to_string(held) + " bytes of checkpoints; " + std::to_string(size) +
                    " more would pass the " + std::to_string(quotas_.max_run_checkpoint_bytes) +
                    " a run may hold (--max-run-checkpoint-mb): prune its old ones");
  }
}

std::int64_t RunStore::insert_checkpoint(const RunRecord& run, long long env_steps,
                                         double eval_success, std::span<const std::uint8_t> blob,
                                         const TrainerCounters* unevaluated) {
  require_checkpoint_quota(run, blob.size());
  auto st = db_.prepare(
      "INSERT INTO checkpoints (run_id, role, env_steps, eval_success, checksum, size_bytes, "
      "blob, created_ms, episodes, updates, wall_s, eval_wall_s) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  st.bind(1, run.id)
      .bind(2, run.spec.role)
      .bind(3, static_cast<std::int64_t>(env_steps))
      .bind(4, eval_success)
      .bind(5, fnv1a64_hex(blob))
      .bind(6, static_cast<std::int64_t>(blob.size()))
      .bind_blob(7, blob)
      .bind(8, now_ms());
  if (unevaluated) {
    st.bind(9, static_cast<std::int64_t>(unevaluated->episodes))
        .bind(10, static_cast<std::int64_t>(unevaluated->updates))
        .bind(11, unevaluated->wall_s)
        .bind(12, unevaluated->eval_wall_s);
  } else {
    st.bind_null(9).bind_null(10).bind_null(11).bind_null(12);
  }
  st.run();
  return db_.last_insert_id();
}

CheckpointInfo RunStore::checkpoint_info(std::int64_t checkpoint_id) {
  auto st =
      db_.prepare(std::string("SELECT ") + kCheckpointColumns + " FROM checkpoints WHERE id = ?");
  st.bind(1, checkpoint_id);
  if (!st.step())
    throw Error(ErrorCode::kNotFound, "checkpoint " + std::to_string(checkpoint_id) +
                                          " not found in store " + db_.path());
  return read_checkpoint_info(st);
}

Checkpoint RunStore::load_checkpoint(std::int64_t checkpoint_id) {
  ReadTransaction snapshot(db_);  // the info and the blob of one version of the row
  Checkpoint out;
  out.info = checkpoint_info(checkpoint_id);
  auto st = db_.prepare("SELECT blob FROM checkpoints WHERE id = ?");
  st.bind(1, checkpoint_id);
  if (!st.step()) {
    throw Error(ErrorCode::kNotFound, "checkpoint " + std::to_string(checkpoint_id) +
                                          " not found in store " + db_.path());
  }
  out.blob = st.column_blob(0);
  if (static_cast<std::int64_t>(out.blob.size()) != out.info.size_bytes ||
      fnv1a64_hex(out.blob) != out.info.checksum) {
    throw Error(ErrorCode::kDataLoss,
                "checkpoint " + std::to_string(checkpoint_id) +
                    " is corrupted: its blob no longer matches its checksum " + out.info.checksum);
  }
  return out;
}

std::optional<CheckpointInfo> RunStore::latest_checkpoint(std::int64_t run_id) {
  get_run(run_id);
  auto st = db_.prepare(std::string("SELECT ") + kCheckpointColumns +
                        " FROM checkpoints WHERE run_id = ? ORDER BY env_steps DESC, id DESC "
                        "LIMIT 1");
  st.bind(1, run_id);
  if (!st.step()) return std::nullopt;
  return read_checkpoint_info(st);
}

std::vector<CheckpointInfo> RunStore::checkpoints(std::int64_t run_id) {
  get_run(run_id);
  auto st = db_.prepare(std::string("SELECT ") + kCheckpointColumns +
                        " FROM checkpoints WHERE run_id = ? ORDER BY env_steps, id");
  st.bind(1, run_id);
  std::vector<CheckpointInfo> out;
  while (st.step()) out.push_back(read_checkpoint_info(st));
  return out;
}

namespace {

// A promotion sets one checkpoint per role: two of one role in one call are refused.
void require_one_per_role(const std::vector<CheckpointInfo>& infos, std::string_view field) {
  for (std::size_t i = 0; i < infos.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (infos[j].role == infos[i].role) {
        throw_invalid_argument(field, "at most one checkpoint per role",
                               "checkpoints " + std::to_string(infos[j].id) + " and " +
                                   std::to_string(infos[i].id) + ", both " + infos[i].role);
      }
    }
  }
}

}  // namespace

std::vector<std::int64_t> RunStore::import_finished(std::span<const FinishedRun> runs, bool promote,
                                                    const std::string& by) {
  for (const FinishedRun& run : runs) {
    require_spec(run.spec);
    if (run.blob.empty() && !run.read_blob)
      throw_invalid_argument("checkpoint", "a non-empty blob", "0 bytes");
  }
  Transaction tx(db_);
  std::vector<std::int64_t> ids;
  std::vector<CheckpointInfo> infos;
  for (const FinishedRun& run : runs) {
    if (run.spec.parent_checkpoint_id) checkpoint_info(*run.spec.parent_checkpoint_id);
    // Finished at once, in the transaction that stores its checkpoint: no training server
    // ever sees it pending, so none takes it for an interrupted run to resume.
    const std::int64_t run_id = insert_run(run.spec, RunState::kSucceeded);
    std::vector<std::uint8_t> scratch;  // one spooled checkpoint at a time
    const auto& blob = run.bytes(scratch);
    if (blob.empty()) throw_invalid_argument("checkpoint", "a non-empty blob", "0 bytes");
    ids.push_back(insert_checkpoint(get_run(run_id), 0, 0.0, blob));
    infos.push_back(checkpoint_info(ids.back()));
  }
  if (promote) {
    require_one_per_role(infos, "runs");
    const Millis now = now_ms();
    for (const CheckpointInfo& info : infos) upsert_promotion(info, now, by);
  }
  tx.commit();
  return ids;
}

void RunStore::upsert_promotion(const CheckpointInfo& info, Millis now, const std::string& by) {
  auto st = db_.prepare(
      "INSERT INTO promotions (role, checkpoint_id, promoted_ms, promoted_by) VALUES (?, ?, ?, ?) "
      "ON CONFLICT (role) DO UPDATE SET checkpoint_id = excluded.checkpoint_id, "
      "promoted_ms = excluded.promoted_ms, promoted_by = excluded.promoted_by");
  st.bind(1, info.role).bind(2, info.id).bind(3, now).bind(4, by);
  st.run();
}

std::vector<Promotion> RunStore::promote(std::span<const std::int64_t> checkpoint_ids,
                                         const std::string& by) {
  if (checkpoint_ids.empty())
    throw_invalid_argument("checkpoint_ids", "at least one checkpoint id", "none");
  std::vector<CheckpointInfo> infos;
  for (const std::int64_t id : checkpoint_ids)
    infos.push_back(load_checkpoint(id).info);  // never promote what cannot be served
  require_one_per_role(infos, "checkpoint_ids");
  Transaction tx(db_);
  const Millis now = now_ms();
  std::vector<Promotion> out;
  for (const CheckpointInfo& info : infos) {
    checkpoint_info(info.id);  // NOT_FOUND if deleted since it was verified
    upsert_promotion(info, now, by);
    out.push_back({info.role, info.id, now, by});
  }
  tx.commit();
  return out;
}

std::optional<Promotion> RunStore::promoted(const std::string& role) {
  if (!is_known_role(role))
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + role + "\"");
  auto st = db_.prepare(
      "SELECT role, checkpoint_id, promoted_ms, promoted_by FROM promotions WHERE role = ?");
  st.bind(1, role);
  if (!st.step()) return std::nullopt;
  return Promotion{st.column_text(0), st.column_int(1), st.column_int(2), st.column_text(3)};
}

std::vector<Promotion> RunStore::promotions() {
  auto st = db_.prepare(
      "SELECT role, checkpoint_id, promoted_ms, promoted_by FROM promotions ORDER BY role");
  std::vector<Promotion> out;
  while (st.step())
    out.push_back({st.column_text(0), st.column_int(1), st.column_int(2), st.column_text(3)});
  return out;
}

namespace {

// The checkpoints retention keeps (the run's last ?1 by steps, its best, the promoted
// ones, and those another run starts from: its parent, or experts it sequences or runs
// after, recorded in its config).
constexpr const char* kKeptCheckpoints = R"sql(
SELECT id FROM (SELECT id, ROW_NUMBER() OVER (PARTITION BY run_id
                ORDER BY env_steps DESC, id DESC) AS rank FROM checkpoints) WHERE rank <= ?1
UNION SELECT id FROM (SELECT id, ROW_NUMBER() OVER (PARTITION BY run_id
                ORDER BY eval_success DESC, env_steps DESC, id DESC) AS rank FROM checkpoints
                WHERE episodes IS NULL)
      WHERE rank = 1
UNION SELECT checkpoint_id FROM promotions
UNION SELECT parent_checkpoint_id FROM runs WHERE parent_checkpoint_id IS NOT NULL
UNION SELECT CAST(e.value AS INTEGER)
      FROM (SELECT config_json FROM runs WHERE json_valid(config_json)) AS r,
           json_each(r.config_json, '$.checkpoints.experts') AS e
)sql";

}  // namespace

GcReport RunStore::prune_where(std::string_view run_condition, std::optional<std::int64_t> run_id,
                               const RetentionPolicy& policy) {
  if (policy.keep_last < 1)
    throw_invalid_argument("keep_last", "at least 1 checkpoint per run",
                           std::to_string(policy.keep_last));
  GcReport report;
  Transaction tx(db_);
  auto doomed =
      db_.prepare("SELECT id, size_bytes FROM checkpoints WHERE " + std::string(run_condition) +
                  " AND id NOT IN (" + kKeptCheckpoints + ")");
  doomed.bind(1, static_cast<std::int64_t>(policy.keep_last));
  if (run_id) doomed.bind(2, *run_id);
  std::vector<std::int64_t> ids;
  while (doomed.step()) {
    ids.push_back(doomed.column_int(0));
    report.bytes_deleted += doomed.column_int(1);
  }
  auto erase = db_.prepare("DELETE FROM checkpoints WHERE id = ?");
  for (const std::int64_t id : ids) {
    erase.reset();
    erase.bind(1, id);
    erase.run();
  }
  tx.commit();
  report.checkpoints_deleted = static_cast<std::int64_t>(ids.size());
  return report;
}

GcReport RunStore::prune_checkpoints(std::int64_t run_id, const RetentionPolicy& policy) {
  get_run(run_id);
  return prune_where("run_id = ?2", run_id, policy);
}

GcReport RunStore::collect_garbage(const RetentionPolicy& policy) {
  GcReport report = prune_where("1", std::nullopt, policy);
  const std::int64_t before = db_.pragma_int("page_count");
  if (db_.pragma_int("auto_vacuum") == 2) {
    db_.execute("PRAGMA incremental_vacuum");  // gives the free pages back
  } else {
    // A file created before incremental auto-vacuum: rewritten once (VACUUM, seconds for
    // hundreds of MB; writers wait), after which its free pages go back as above.
    db_.execute("PRAGMA auto_vacuum = INCREMENTAL");
    db_.execute("VACUUM");
  }
  report.pages_freed = before - db_.pragma_int("page_count");
  db_.execute("PRAGMA wal_checkpoint(TRUNCATE)");
  return report;
}

BackupReport RunStore::backup(const std::string& destination) {
  if (db_.path() == ":memory:")
    throw Error(ErrorCode::kFailedPrecondition, "backup: an in-memory store has no file to copy");
  return backup_store(db_.path(), destination);
}

}  // namespace pnp::store
