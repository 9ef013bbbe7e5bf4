#pragma once
// A thin RAII layer over SQLite: a connection configured the way the store needs it (WAL
// journal, busy timeout, foreign keys), prepared statements, and transactions that roll
// back unless committed. A connection belongs to one thread at a time.

#include <sqlite3.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pnp::store {

class Statement;

class Database {
 public:
  // Opens (creating if needed) the file at `path`; ":memory:" for a private in-memory
  // database. Throws UNAVAILABLE (ErrorCode::kUnavailable) if it cannot be opened.
  explicit Database(const std::string& path,
                    std::chrono::milliseconds busy_timeout = std::chrono::seconds(5));

  void execute(std::string_view sql);  // one or more statements, no results
  Statement prepare(std::string_view sql);
  std::int64_t last_insert_id() const;
  int changes() const;
  sqlite3* handle() const { return db_.get(); }
  const std::string& path() const { return path_; }

 private:
  struct Close {
    void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
  };
  std::unique_ptr<sqlite3, Close> db_;
  std::string path_;
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

}  // namespace pnp::store
