#pragma once
// A thin RAII layer over SQLite: a connection configured the way the store needs it (WAL
// journal confirmed, synchronous FULL, busy timeout, foreign keys), prepared statements,
// and transactions that roll back unless committed. A connection belongs to one thread at
// a time.

#include <sqlite3.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/error.h"

namespace pnp::store {

class Statement;

// Anything SQLite itself refused or failed at (the disk, the file, a lock, a constraint):
// what a server reports as its store's health, apart from the caller's own mistakes.
class StoreError : public Error {
 public:
  StoreError(ErrorCode code, const std::string& message) : Error(code, message) {}
};

// SQLITE_BUSY / SQLITE_LOCKED after the busy timeout: another connection holds the lock.
// UNAVAILABLE, and retryable (store/retry.h): nothing was written.
class BusyError : public StoreError {
 public:
  explicit BusyError(const std::string& message) : StoreError(ErrorCode::kUnavailable, message) {}
};

enum class Access {
  kReadWrite,  // creates the file if needed and sets it up (WAL)
  kReadOnly,   // never writes: for readers, and for files they may not write
};

// kFull: a commit is on disk when it is acknowledged, so a power loss keeps it. kNormal
// keeps commits across a process crash only; it exists so that pnp-bench-store can
// measure what kFull costs.
enum class Sync { kFull, kNormal };

struct DatabaseOptions {
  Access access = Access::kReadWrite;
  Sync sync = Sync::kFull;
  std::chrono::milliseconds busy_timeout = std::chrono::seconds(5);
  // A registered SQLite VFS by name (empty: the default). Tests use one that models a
  // power loss (tests/core/store/power_loss_vfs.h).
  std::string vfs{};
};

class Database {
 public:
  // Opens the file at `path`; ":memory:" for a private in-memory database. Errors name
  // the path: a missing file opened read-only is NOT_FOUND, a directory that refuses the
  // file FAILED_PRECONDITION, a file that is not a database DATA_LOSS, a file that cannot
  // hold a WAL journal FAILED_PRECONDITION.
  explicit Database(const std::string& path, const DatabaseOptions& options = {});

  void execute(std::string_view sql);  // one or more statements, no results
  Statement prepare(std::string_view sql);
  std::int64_t pragma_int(std::string_view pragma);  // PRAGMA <pragma>, first column
  std::int64_t last_insert_id() const;
  int changes() const;
  sqlite3* handle() const { return db_.get(); }
  const std::string& path() const { return path_; }
  Access access() const { return access_; }

 private:
  struct Close {
    void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
  };
  std::unique_ptr<sqlite3, Close> db_;
  std::string path_;
  Access access_;
};

class Statement {
 public:
  Statement(sqlite3* db, std::string_view sql);

  // Binders take 1-based positions, as SQLite does; they return *this to chain.
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, double value);
  Statement& bind(int index, std::string_view text);
  Statement& bind_blob(int index, std::span<const std::uint8_t> bytes);
  Statement& bind_null(int index);
  template <typename T>
  Statement& bind_optional(int index, const std::optional<T>& value) {
    return value ? bind(index, *value) : bind_null(index);
  }

  bool step();  // true while a row is available
  void run();   // steps a statement that returns no rows
  void reset();

  bool is_null(int column) const;
  std::int64_t column_int(int column) const;
  double column_double(int column) const;
  std::string column_text(int column) const;
  std::vector<std::uint8_t> column_blob(int column) const;

 private:
  struct Finalize {
    void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
  };
  std::unique_ptr<sqlite3_stmt, Finalize> stmt_;
  sqlite3* db_;
};

// BEGIN IMMEDIATE on construction (the write lock is taken at once, so two writers never
// deadlock half-way); ROLLBACK on destruction unless commit() was called.
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit();

 private:
  Database& db_;
  bool done_ = false;
};

// BEGIN (deferred): several reads see one snapshot of the database, whatever commits
// meanwhile. Takes no write lock; ends on destruction. Inside another transaction it does
// nothing (that transaction is already one snapshot).
class ReadTransaction {
 public:
  explicit ReadTransaction(Database& db);
  ~ReadTransaction();
  ReadTransaction(const ReadTransaction&) = delete;
  ReadTransaction& operator=(const ReadTransaction&) = delete;

 private:
  Database& db_;
  bool owns_;
};

}  // namespace pnp::store
