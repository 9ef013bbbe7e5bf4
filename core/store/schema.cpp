#include "store/schema.h"

#include <array>
#include <string>
#include <string_view>

#include "common/error.h"
#include "store/retry.h"

namespace pnp::store {
namespace {

// Append only: a migration that has shipped is never edited.
constexpr std::array<std::string_view, 9> kMigrations{
    R"sql(
CREATE TABLE runs (
  id INTEGER PRIMARY KEY,
  role TEXT NOT NULL CHECK (role IN ('approach', 'manipulate', 'retract', 'hlc', 'e2e')),
  algorithm TEXT NOT NULL,
  robot TEXT NOT NULL,
  object TEXT NOT NULL,
  seed INTEGER NOT NULL,
  config_json TEXT NOT NULL,
  code_commit TEXT NOT NULL,
  parent_checkpoint_id INTEGER REFERENCES checkpoints(id),
  state TEXT NOT NULL
    CHECK (state IN ('pending', 'running', 'succeeded', 'failed', 'cancelled')),
  error TEXT NOT NULL DEFAULT '',
  env_steps INTEGER NOT NULL DEFAULT 0,
  last_success REAL NOT NULL DEFAULT 0,
  reached INTEGER NOT NULL DEFAULT 0,
  steps_to_target INTEGER,
  created_ms INTEGER NOT NULL,
  updated_ms INTEGER NOT NULL,
  finished_ms INTEGER
);
CREATE INDEX runs_by_role ON runs (role, id);

CREATE TABLE metrics (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  env_steps INTEGER NOT NULL,
  episodes INTEGER NOT NULL,
  wall_s REAL NOT NULL,
  task_success REAL NOT NULL,
  subtask_success REAL NOT NULL,
  sampled_success REAL NOT NULL,
  critic_loss REAL NOT NULL,
  actor_loss REAL NOT NULL,
  updates INTEGER NOT NULL,
  PRIMARY KEY (run_id, env_steps)
);

CREATE TABLE checkpoints (
  id INTEGER PRIMARY KEY,
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  role TEXT NOT NULL,
  env_steps INTEGER NOT NULL,
  eval_success REAL NOT NULL,
  checksum TEXT NOT NULL,
  size_bytes INTEGER NOT NULL,
  blob BLOB NOT NULL,
  created_ms INTEGER NOT NULL
);
CREATE INDEX checkpoints_by_run ON checkpoints (run_id, id);

CREATE TABLE promotions (
  role TEXT PRIMARY KEY,
  checkpoint_id INTEGER NOT NULL REFERENCES checkpoints(id),
  promoted_ms INTEGER NOT NULL
);
)sql",
    // 2: the GEMM path a run was trained on.
    R"sql(
ALTER TABLE runs ADD COLUMN gemm_path TEXT NOT NULL DEFAULT '';
)sql",
    // 3: the score the run's stop rule compares with its target (experts: the lower of task
    // and subtask success), beside task success. NULL for evaluations from before it was kept.
    R"sql(
ALTER TABLE metrics ADD COLUMN stop_score REAL;
ALTER TABLE runs ADD COLUMN last_score REAL;
)sql",
    // 4: run ownership (a training server claims a run with a lease it renews; another
    // server of the role takes it over only once the lease has expired), and ids that are
    // never reused (AUTOINCREMENT: a deleted run's or checkpoint's id never names another
    // one). SQLite adds AUTOINCREMENT only to a new table, so both are rebuilt; the store
    // turns foreign keys off around migrations for it (store/schema.cpp).
    R"sql(
CREATE TABLE runs_v4 (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  role TEXT NOT NULL CHECK (role IN ('approach', 'manipulate', 'retract', 'hlc', 'e2e')),
  algorithm TEXT NOT NULL,
  robot TEXT NOT NULL,
  object TEXT NOT NULL,
  seed INTEGER NOT NULL,
  config_json TEXT NOT NULL,
  code_commit TEXT NOT NULL,
  parent_checkpoint_id INTEGER REFERENCES checkpoints(id),
  state TEXT NOT NULL
    CHECK (state IN ('pending', 'running', 'succeeded', 'failed', 'cancelled')),
  error TEXT NOT NULL DEFAULT '',
  env_steps INTEGER NOT NULL DEFAULT 0,
  last_success REAL NOT NULL DEFAULT 0,
  reached INTEGER NOT NULL DEFAULT 0,
  steps_to_target INTEGER,
  created_ms INTEGER NOT NULL,
  updated_ms INTEGER NOT NULL,
  finished_ms INTEGER,
  gemm_path TEXT NOT NULL DEFAULT '',
  last_score REAL,
  owner TEXT,
  lease_expires_ms INTEGER
);
INSERT INTO runs_v4 (id, role, algorithm, robot, object, seed, config_json, code_commit,
  parent_checkpoint_id, state, error, env_steps, last_success, reached, steps_to_target,
  created_ms, updated_ms, finished_ms, gemm_path, last_score)
SELECT id, role, algorithm, robot, object, seed, config_json, code_commit,
  parent_checkpoint_id, state, error, env_steps, last_success, reached, steps_to_target,
  created_ms, updated_ms, finished_ms, gemm_path, last_score FROM runs;
DROP TABLE runs;
ALTER TABLE runs_v4 RENAME TO runs;
CREATE INDEX runs_by_role ON runs (role, id);
CREATE INDEX runs_by_state ON runs (role, state, id);

CREATE TABLE checkpoints_v4 (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  role TEXT NOT NULL,
  env_steps INTEGER NOT NULL,
  eval_success REAL NOT NULL,
  checksum TEXT NOT NULL,
  size_bytes INTEGER NOT NULL,
  blob BLOB NOT NULL,
  created_ms INTEGER NOT NULL
);
INSERT INTO checkpoints_v4 SELECT id, run_id, role, env_steps, eval_success, checksum,
  size_bytes, blob, created_ms FROM checkpoints;
DROP TABLE checkpoints;
ALTER TABLE checkpoints_v4 RENAME TO checkpoints;
CREATE INDEX checkpoints_by_run ON checkpoints (run_id, env_steps, id);
)sql",
    // 5: weights saved between evaluations (a trainer stopped by a shutdown or a cancel)
    // carry the counters it resumes from; NULL for an evaluated checkpoint, whose counters
    // are its evaluation's.
    R"sql(
ALTER TABLE checkpoints ADD COLUMN episodes INTEGER;
ALTER TABLE checkpoints ADD COLUMN updates INTEGER;
ALTER TABLE checkpoints ADD COLUMN wall_s REAL;
ALTER TABLE checkpoints ADD COLUMN eval_wall_s REAL;
)sql",
    // 6: the audit trail of operator and robot calls, and who promoted each checkpoint.
    R"sql(
CREATE TABLE audit (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  ts_ms INTEGER NOT NULL,
  service TEXT NOT NULL,
  principal TEXT NOT NULL,
  peer TEXT NOT NULL,
  rpc TEXT NOT NULL,
  request TEXT NOT NULL,
  code TEXT NOT NULL
);
CREATE INDEX audit_by_time ON audit (ts_ms);
ALTER TABLE promotions ADD COLUMN promoted_by TEXT NOT NULL DEFAULT '';
)sql",
    // 7: who wrote each audit record and when the store received it, as the store saw it
    // (a forwarding server names the principal and time of its callers' records); the
    // idempotency key a run was created with (a retried creation returns that run).
    R"sql(
ALTER TABLE audit ADD COLUMN recorded_by TEXT NOT NULL DEFAULT '';
ALTER TABLE audit ADD COLUMN received_ms INTEGER NOT NULL DEFAULT 0;
UPDATE audit SET received_ms = ts_ms;
ALTER TABLE runs ADD COLUMN request_id TEXT;
CREATE UNIQUE INDEX runs_by_request_id ON runs (request_id) WHERE request_id IS NOT NULL;
)sql",
    // 8: who created each run, as the store server authenticated them (the quota of open
    // runs per principal); empty for runs created before, or without an auth policy.
    R"sql(
ALTER TABLE runs ADD COLUMN created_by TEXT NOT NULL DEFAULT '';
CREATE INDEX runs_by_creator ON runs (created_by, state);
)sql",
    // 9: where each run's wall time went, by phase (Store::add_wall_time); zero for runs
    // trained before.
    R"sql(
ALTER TABLE runs ADD COLUMN wall_rollout_s REAL NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN wall_update_s REAL NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN wall_eval_s REAL NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN wall_report_s REAL NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN wall_other_s REAL NOT NULL DEFAULT 0;
)sql",
};

int user_version(Database& db) {
  auto st = db.prepare("PRAGMA user_version");
  st.step();
  return static_cast<int>(st.column_int(0));
}

}  // namespace

int schema_version() {
  return static_cast<int>(kMigrations.size());
}

namespace {

[[noreturn]] void refuse_newer(Database& db, int current) {
  throw Error(ErrorCode::kFailedPrecondition,
              "database " + db.path() + " has schema version " + std::to_string(current) +
                  ", newer than this build's " + std::to_string(schema_version()) +
                  ": use a newer build");
}

// Foreign keys off while migrations rebuild tables (dropping a table with them on would
// cascade-delete the rows that reference it); the setting is a no-op inside a transaction,
// hence around it.
class ForeignKeysOff {
 public:
  explicit ForeignKeysOff(Database& db) : db_(db) { db_.execute("PRAGMA foreign_keys = OFF"); }
  ~ForeignKeysOff() {
    try {
      db_.execute("PRAGMA foreign_keys = ON");
    } catch (...) {  // the connection is unusable then; its next statement says so
    }
  }
  ForeignKeysOff(const ForeignKeysOff&) = delete;
  ForeignKeysOff& operator=(const ForeignKeysOff&) = delete;

 private:
  Database& db_;
};

}  // namespace

void migrate(Database& db) {
  migrate_to(db, schema_version());
}

void migrate_to(Database& db, int target) {
  if (target < 0 || target > schema_version())
    throw_invalid_argument("schema version", "0 to " + std::to_string(schema_version()),
                           std::to_string(target));
  // Read without a lock first: a current database is opened without ever taking the write
  // lock, so a server starts while another process is writing.
  const int seen = user_version(db);
  if (seen > schema_version()) refuse_newer(db, seen);
  if (seen >= target) return;
  if (db.access() == Access::kReadOnly) {
    throw Error(ErrorCode::kFailedPrecondition,
                "database " + db.path() + " has schema version " + std::to_string(seen) +
                    ", older than this build's " + std::to_string(schema_version()) +
                    ": open it once read-write (any training server) to migrate it");
  }
  ForeignKeysOff keys_off(db);
  // The version is re-read under the write lock: processes opening a new file together
  // (the platform starts its services at once) must not both run the same migration. One
  // of them may hold the lock for seconds (migration 4 copies every checkpoint): the
  // others wait for it rather than fail to start.
  with_retry(RetryPolicy{.budget = std::chrono::minutes(2)}, [&] {
    Transaction tx(db);
    const int current = user_version(db);
    if (current > schema_version()) refuse_newer(db, current);
    for (int v = current; v < target; ++v) {
      db.execute(kMigrations[static_cast<std::size_t>(v)]);
      db.execute("PRAGMA user_version = " + std::to_string(v + 1));
    }
    auto violations = db.prepare("PRAGMA foreign_key_check");
    if (violations.step()) {
      throw Error(ErrorCode::kDataLoss, "database " + db.path() + ": table " +
                                            violations.column_text(0) +
                                            " has rows whose references are missing");
    }
    tx.commit();
  });
}

}  // namespace pnp::store
