#include "store/run_store.h"

#include <chrono>

#include "common/checksum.h"
#include "common/error.h"
#include "store/schema.h"

namespace pnp::store {
namespace {

constexpr const char* kRunColumns =
    "id, role, algorithm, robot, object, seed, config_json, code_commit, parent_checkpoint_id, "
    "state, error, env_steps, last_success, reached, steps_to_target, created_ms, updated_ms, "
    "finished_ms, gemm_path, last_score";

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
  return r;
}

constexpr const char* kCheckpointColumns =
    "id, run_id, role, env_steps, eval_success, checksum, size_bytes, created_ms";

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

RunStore::RunStore(const std::string& path) : db_(path) {
  migrate(db_);
}

RunRecord RunStore::create_run(const RunSpec& spec) {
  require_spec(spec);
  Transaction tx(db_);
  if (spec.parent_checkpoint_id) checkpoint_info(*spec.parent_checkpoint_id);  // NOT_FOUND
  const Millis now = now_ms();
  auto st = db_.prepare(
      "INSERT INTO runs (role, algorithm, robot, object, seed, config_json, code_commit, "
      "parent_checkpoint_id, state, created_ms, updated_ms, gemm_path) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, 'pending', ?, ?, ?)");
  st.bind(1, spec.role)
      .bind(2, spec.algorithm)
      .bind(3, spec.robot)
      .bind(4, spec.object)
      .bind(5, static_cast<std::int64_t>(spec.seed))
      .bind(6, spec.config_json)
      .bind(7, spec.code_commit)
      .bind_optional(8, spec.parent_checkpoint_id)
      .bind(9, now)
      .bind(10, now)
      .bind(11, spec.gemm_path);
  st.run();
  const std::int64_t id = db_.last_insert_id();
  tx.commit();
  return get_run(id);
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

RunRecord RunStore::set_state(std::int64_t id, RunState state, const std::string& error) {
  Transaction tx(db_);
  const RunRecord current = get_run(id);
  if (is_terminal(current.state) && current.state != state) {
    throw Error(ErrorCode::kFailedPrecondition, "run " + std::to_string(id) + " is already " +
                                                    std::string(run_state_name(current.state)) +
                                                    "; it cannot become " +
                                                    std::string(run_state_name(state)));
  }
  const Millis now = now_ms();
  auto st = db_.prepare(
      "UPDATE runs SET state = ?, error = ?, updated_ms = ?, "
      "finished_ms = CASE WHEN ? THEN COALESCE(finished_ms, ?) ELSE NULL END WHERE id = ?");
  st.bind(1, run_state_name(state))
      .bind(2, error)
      .bind(3, now)
      .bind(4, static_cast<std::int64_t>(is_terminal(state)))
      .bind(5, now)
      .bind(6, id);
  st.run();
  tx.commit();
  return get_run(id);
}

void RunStore::record_metric(std::int64_t run_id, const MetricPoint& p, bool reached,
                             std::optional<long long> steps_to_target) {
  Transaction tx(db_);
  insert_metric(run_id, p, reached, steps_to_target);
  tx.commit();
}

CheckpointInfo RunStore::record_evaluation(std::int64_t run_id, const MetricPoint& point,
                                           std::span<const std::uint8_t> blob, bool reached,
                                           std::optional<long long> steps_to_target) {
  if (blob.empty()) throw_invalid_argument("checkpoint", "a non-empty blob", "0 bytes");
  Transaction tx(db_);
  insert_metric(run_id, point, reached, steps_to_target);
  const std::int64_t id = insert_checkpoint(run_id, point.env_steps, point.task_success, blob);
  tx.commit();
  return checkpoint_info(id);
}

void RunStore::insert_metric(std::int64_t run_id, const MetricPoint& p, bool reached,
                             std::optional<long long> steps_to_target) {
  const RunRecord run = get_run(run_id);
  if (is_terminal(run.state)) {
    throw Error(ErrorCode::kFailedPrecondition, "run " + std::to_string(run_id) + " is " +
                                                    std::string(run_state_name(run.state)) +
                                                    ": it takes no more metrics");
  }
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

std::vector<MetricPoint> RunStore::metrics(std::int64_t run_id) {
  get_run(run_id);  // NOT_FOUND for an unknown run, rather than an empty curve
  auto st = db_.prepare(
      "SELECT env_steps, episodes, wall_s, task_success, subtask_success, sampled_success, "
      "critic_loss, actor_loss, updates, stop_score FROM metrics WHERE run_id = ? ORDER BY "
      "env_steps");
  st.bind(1, run_id);
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

CheckpointInfo RunStore::save_checkpoint(std::int64_t run_id, long long env_steps,
                                         double eval_success, std::span<const std::uint8_t> blob) {
  if (blob.empty()) throw_invalid_argument("checkpoint", "a non-empty blob", "0 bytes");
  Transaction tx(db_);
  const std::int64_t id = insert_checkpoint(run_id, env_steps, eval_success, blob);
  tx.commit();
  return checkpoint_info(id);
}

std::int64_t RunStore::insert_checkpoint(std::int64_t run_id, long long env_steps,
                                         double eval_success, std::span<const std::uint8_t> blob) {
  const RunRecord run = get_run(run_id);
  auto st = db_.prepare(
      "INSERT INTO checkpoints (run_id, role, env_steps, eval_success, checksum, size_bytes, "
      "blob, created_ms) VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
  st.bind(1, run_id)
      .bind(2, run.spec.role)
      .bind(3, static_cast<std::int64_t>(env_steps))
      .bind(4, eval_success)
      .bind(5, fnv1a64_hex(blob))
      .bind(6, static_cast<std::int64_t>(blob.size()))
      .bind_blob(7, blob)
      .bind(8, now_ms());
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
  Checkpoint out;
  out.info = checkpoint_info(checkpoint_id);
  auto st = db_.prepare("SELECT blob FROM checkpoints WHERE id = ?");
  st.bind(1, checkpoint_id);
  st.step();
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
  auto all = checkpoints(run_id);
  if (all.empty()) return std::nullopt;
  return all.back();
}

std::vector<CheckpointInfo> RunStore::checkpoints(std::int64_t run_id) {
  get_run(run_id);
  auto st = db_.prepare(std::string("SELECT ") + kCheckpointColumns +
                        " FROM checkpoints WHERE run_id = ? ORDER BY id");
  st.bind(1, run_id);
  std::vector<CheckpointInfo> out;
  while (st.step()) out.push_back(read_checkpoint_info(st));
  return out;
}

Promotion RunStore::promote(std::int64_t checkpoint_id) {
  load_checkpoint(checkpoint_id);  // never promote what could not be served
  Transaction tx(db_);
  const CheckpointInfo info = checkpoint_info(checkpoint_id);
  auto st = db_.prepare(
      "INSERT INTO promotions (role, checkpoint_id, promoted_ms) VALUES (?, ?, ?) "
      "ON CONFLICT (role) DO UPDATE SET checkpoint_id = excluded.checkpoint_id, "
      "promoted_ms = excluded.promoted_ms");
  const Millis now = now_ms();
  st.bind(1, info.role).bind(2, checkpoint_id).bind(3, now);
  st.run();
  tx.commit();
  return {info.role, checkpoint_id, now};
}

std::optional<Promotion> RunStore::promoted(const std::string& role) {
  if (!is_known_role(role))
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + role + "\"");
  auto st = db_.prepare("SELECT role, checkpoint_id, promoted_ms FROM promotions WHERE role = ?");
  st.bind(1, role);
  if (!st.step()) return std::nullopt;
  return Promotion{st.column_text(0), st.column_int(1), st.column_int(2)};
}

std::vector<Promotion> RunStore::promotions() {
  auto st = db_.prepare("SELECT role, checkpoint_id, promoted_ms FROM promotions ORDER BY role");
  std::vector<Promotion> out;
  while (st.step()) out.push_back({st.column_text(0), st.column_int(1), st.column_int(2)});
  return out;
}

}  // namespace pnp::store
