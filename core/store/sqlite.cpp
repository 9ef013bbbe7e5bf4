#include "store/sqlite.h"

#include <chrono>
#include <filesystem>
#include <system_error>

#include "common/error.h"
#include "store/retry.h"

namespace pnp::store {
namespace {

std::string file_of(sqlite3* db) {
  const char* name = db ? sqlite3_db_filename(db, "main") : nullptr;
  return name && *name ? name : ":memory:";
}

// What went wrong, in the terms a caller acts on: BUSY and LOCKED are retryable (another
// connection holds the lock past the busy timeout); a full disk is RESOURCE_EXHAUSTED and a
// read-only file FAILED_PRECONDITION (retrying will not help, an operator must); a damaged
// file is DATA_LOSS. Every message names the file.
[[noreturn]] void fail(sqlite3* db, int code, std::string_view what, std::string_view file = {}) {
  std::string message = "store " + (file.empty() ? file_of(db) : std::string(file)) + ": " +
                        std::string(what) + ": " + (db ? sqlite3_errmsg(db) : sqlite3_errstr(code));
  // The operating system's word for an I/O failure says which: no space, file too large...
  const int os_error = db ? sqlite3_system_errno(db) : 0;
  const int primary = code & 0xff;
  if (os_error != 0 && (primary == SQLITE_IOERR || primary == SQLITE_FULL ||
                        primary == SQLITE_CANTOPEN || primary == SQLITE_READONLY))
    message += " (" + std::error_code(os_error, std::generic_category()).message() + ")";
  switch (primary) {
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      throw BusyError(message);
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      throw StoreError(ErrorCode::kDataLoss, message);
    case SQLITE_CONSTRAINT:
      throw StoreError(ErrorCode::kFailedPrecondition, message);
    case SQLITE_FULL:
      throw StoreError(ErrorCode::kResourceExhausted, message + " (the disk is full)");
    case SQLITE_READONLY:
      throw StoreError(ErrorCode::kFailedPrecondition, message + " (the file is read-only)");
    case SQLITE_CANTOPEN:
      throw StoreError(ErrorCode::kFailedPrecondition, message);
    case SQLITE_IOERR:
      throw StoreError(ErrorCode::kUnavailable, message);
    default:
      throw StoreError(ErrorCode::kInternal, message);
  }
}

std::string first_text(sqlite3* db, const std::string& sql) {
  Statement st(db, sql);
  return st.step() ? st.column_text(0) : std::string();
}

// Switching a new file to WAL needs an exclusive lock, and SQLite does not call the busy
// handler for it while another connection is creating the same file: the pragma then
// fails at once with BUSY. Retried here for as long as the busy timeout would wait. The
// answer is checked: a filesystem without shared memory keeps the old journal mode, and
// the store would then silently lose WAL's concurrent reads.
void enable_wal(sqlite3* db, std::chrono::milliseconds patience) {
  const std::string mode = with_retry({.budget = patience,
                                       .first_backoff = std::chrono::milliseconds(5),
                                       .max_backoff = std::chrono::milliseconds(5)},
                                      [&] { return first_text(db, "PRAGMA journal_mode = WAL"); });
  if (mode != "wal") {
    throw Error(ErrorCode::kFailedPrecondition,
                "store " + file_of(db) + ": journal_mode is \"" + mode +
                    "\" where \"wal\" is needed: put the database on a local filesystem");
  }
}

// The WAL file is cut back to this size after a checkpoint (it otherwise keeps its
// largest size); 1.1 MB checkpoints make it grow past SQLite's 4 MB autocheckpoint.
constexpr int kJournalSizeLimitBytes = 16 << 20;

}  // namespace

Database::Database(const std::string& path, const DatabaseOptions& options)
    : path_(path), access_(options.access) {
  if (path.empty()) throw_invalid_argument("db path", "a file name or :memory:", "an empty path");
  const bool read_only = options.access == Access::kReadOnly;
  if (read_only && path != ":memory:" && !std::filesystem::exists(path)) {
    throw Error(ErrorCode::kNotFound, "store " + path + ": no such database (opened read-only)");
  }
  sqlite3* raw = nullptr;
  const int flags =
      (read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE) |
      SQLITE_OPEN_NOMUTEX;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags,
                                 options.vfs.empty() ? nullptr : options.vfs.c_str());
  db_.reset(raw);  // closed even when opening failed
  // A connection that failed to open has no file name yet: name the path asked for.
  if (rc != SQLITE_OK) fail(raw, rc, "opening the database", path);
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, static_cast<int>(options.busy_timeout.count()));
  execute("PRAGMA foreign_keys = ON");
  if (read_only) {
    execute("PRAGMA query_only = ON");
    return;
  }
  if (path == ":memory:") return;
  // On a new file only (an existing one keeps its mode, and setting it would wait for the
  // write lock): freed pages can then be given back to the filesystem a few at a time
  // (pnpctl gc) instead of by a full VACUUM.
  if (pragma_int("page_count") == 0) execute("PRAGMA auto_vacuum = INCREMENTAL");
  // WAL: readers never block the writer (the training services write metrics while the
  // inference service and clients read). A file already in WAL mode is left as it is.
  if (first_text(raw, "PRAGMA journal_mode") != "wal") enable_wal(raw, options.busy_timeout);
  // FULL: in WAL mode, NORMAL keeps commits across a process crash but a power loss rolls
  // back every commit since the last checkpoint, acknowledged promotions and final states
  // included. What FULL costs per evaluation is in docs/BENCHMARKS.md (pnp-bench-store).
  execute(options.sync == Sync::kFull ? "PRAGMA synchronous = FULL"
                                      : "PRAGMA synchronous = NORMAL");
  execute("PRAGMA journal_size_limit = " + std::to_string(kJournalSizeLimitBytes));
}

void Database::execute(std::string_view sql) {
  char* message = nullptr;
  const std::string text(sql);
  const int rc = sqlite3_exec(db_.get(), text.c_str(), nullptr, nullptr, &message);
  sqlite3_free(message);  // fail() takes the same text from the connection
  if (rc != SQLITE_OK) fail(db_.get(), rc, "executing \"" + text.substr(0, 60) + "\"");
}

Statement Database::prepare(std::string_view sql) {
  return Statement(db_.get(), sql);
}

std::int64_t Database::pragma_int(std::string_view pragma) {
  auto st = prepare("PRAGMA " + std::string(pragma));
  return st.step() ? st.column_int(0) : 0;
}

std::int64_t Database::last_insert_id() const {
  return sqlite3_last_insert_rowid(db_.get());
}

int Database::changes() const {
  return sqlite3_changes(db_.get());
}

Statement::Statement(sqlite3* db, std::string_view sql) : db_(db) {
  sqlite3_stmt* raw = nullptr;
  const int rc = sqlite3_prepare_v2(db, sql.data(), static_cast<int>(sql.size()), &raw, nullptr);
  stmt_.reset(raw);
  if (rc != SQLITE_OK) fail(db, rc, "preparing \"" + std::string(sql.substr(0, 60)) + "\"");
}

Statement& Statement::bind(int index, std::int64_t value) {
  const int rc = sqlite3_bind_int64(stmt_.get(), index, value);
  if (rc != SQLITE_OK) fail(db_, rc, "binding an integer");
  return *this;
}

Statement& Statement::bind(int index, double value) {
  const int rc = sqlite3_bind_double(stmt_.get(), index, value);
  if (rc != SQLITE_OK) fail(db_, rc, "binding a number");
  return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
  const int rc = sqlite3_bind_text(stmt_.get(), index, text.data(), static_cast<int>(text.size()),
                                   SQLITE_TRANSIENT);
  if (rc != SQLITE_OK) fail(db_, rc, "binding text");
  return *this;
}

Statement& Statement::bind_blob(int index, std::span<const std::uint8_t> bytes) {
  const int rc =
      sqlite3_bind_blob64(stmt_.get(), index, bytes.data(), bytes.size(), SQLITE_TRANSIENT);
  if (rc != SQLITE_OK) fail(db_, rc, "binding a blob");
  return *this;
}

Statement& Statement::bind_null(int index) {
  const int rc = sqlite3_bind_null(stmt_.get(), index);
  if (rc != SQLITE_OK) fail(db_, rc, "binding null");
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_.get());
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  fail(db_, rc, "running a statement");
}

void Statement::run() {
  while (step()) {
  }
}

void Statement::reset() {
  sqlite3_reset(stmt_.get());
  sqlite3_clear_bindings(stmt_.get());
}

bool Statement::is_null(int column) const {
  return sqlite3_column_type(stmt_.get(), column) == SQLITE_NULL;
}

std::int64_t Statement::column_int(int column) const {
  return sqlite3_column_int64(stmt_.get(), column);
}

double Statement::column_double(int column) const {
  return sqlite3_column_double(stmt_.get(), column);
}

std::string Statement::column_text(int column) const {
  const auto* text = sqlite3_column_text(stmt_.get(), column);
  const int size = sqlite3_column_bytes(stmt_.get(), column);
  return text ? std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(size))
              : std::string();
}

std::vector<std::uint8_t> Statement::column_blob(int column) const {
  const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_.get(), column));
  const int size = sqlite3_column_bytes(stmt_.get(), column);
  return data ? std::vector<std::uint8_t>(data, data + size) : std::vector<std::uint8_t>();
}

Transaction::Transaction(Database& db) : db_(db) {
  db_.execute("BEGIN IMMEDIATE");
}

Transaction::~Transaction() {
  if (done_) return;
  try {
    db_.execute("ROLLBACK");
  } catch (...) {  // nothing more can be done from a destructor; SQLite rolls back on close
  }
}

void Transaction::commit() {
  db_.execute("COMMIT");
  done_ = true;
}

ReadTransaction::ReadTransaction(Database& db)
    : db_(db), owns_(sqlite3_get_autocommit(db.handle()) != 0) {
  if (owns_) db_.execute("BEGIN");  // inside a transaction already: that one is the snapshot
}

ReadTransaction::~ReadTransaction() {
  if (!owns_) return;
  try {
    db_.execute("COMMIT");  // a read-only transaction: ends the snapshot, writes nothing
  } catch (...) {           // nothing more can be done from a destructor
  }
}

}  // namespace pnp::store
