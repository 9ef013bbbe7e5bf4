#include "store/schema.h"

#include <array>
#include <string>
#include <string_view>

#include "common/error.h"

namespace pnp::store {
namespace {

// Append only: a migration that has shipped is never edited.
constexpr std::array<std::string_view, 3> kMigrations{
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

void migrate(Database& db) {
  // The version is read under the write lock: processes opening a new file together (the
  // platform starts its services at once) must not both run the same migration.
  Transaction tx(db);
  const int current = user_version(db);
  if (current > schema_version()) {
    throw Error(ErrorCode::kFailedPrecondition,
                "database " + db.path() + " has schema version " + std::to_string(current) +
                    ", newer than this build's " + std::to_string(schema_version()) +
                    ": use a newer build");
  }
  for (int v = current; v < schema_version(); ++v) {
    db.execute(kMigrations[static_cast<std::size_t>(v)]);
    db.execute("PRAGMA user_version = " + std::to_string(v + 1));
  }
  tx.commit();
}

}  // namespace pnp::store
