#pragma once
// Read-only SQL over a store file through the SQLite C API, not core/store: the
// integration tests check what is on disk, as any other reader would find it.

#include <sqlite3.h>

#include <array>
#include <charconv>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace pnp::integration {

// A row as text: NULL as "NULL", integers in decimal, reals in their shortest round-trip
// form (equal text, equal value), text as is, blobs as "blob[<size>]".
using SqlRow = std::vector<std::string>;

class StoreReader {
 public:
  explicit StoreReader(const std::string& path) {
    sqlite3* db = nullptr;
    const int rc = sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
    db_.reset(db);
    if (rc != SQLITE_OK) {
      throw std::runtime_error("cannot open " + path + " read-only: " +
                               (db != nullptr ? sqlite3_errmsg(db) : sqlite3_errstr(rc)));
    }
    sqlite3_busy_timeout(db, 10'000);
  }

  // Every row of `sql`, with `params` bound to its ?s in order.
  std::vector<SqlRow> rows(const std::string& sql,
                           const std::vector<long long>& params = {}) const {
    sqlite3_stmt* raw = nullptr;
    if (sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &raw, nullptr) != SQLITE_OK)
      throw std::runtime_error(sql + ": " + sqlite3_errmsg(db_.get()));
    const std::unique_ptr<sqlite3_stmt, Finalize> statement(raw);
    for (std::size_t i = 0; i < params.size(); ++i)
      sqlite3_bind_int64(raw, static_cast<int>(i + 1), params[i]);
    std::vector<SqlRow> out;
    for (;;) {
      const int rc = sqlite3_step(raw);
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) throw std::runtime_error(sql + ": " + sqlite3_errmsg(db_.get()));
      SqlRow row;
      for (int c = 0; c < sqlite3_column_count(raw); ++c) row.push_back(column(raw, c));
      out.push_back(std::move(row));
    }
    return out;
  }

  // The first column of the only (or first) row; throws if there is none.
  std::string text(const std::string& sql, const std::vector<long long>& params = {}) const {
    const auto result = rows(sql, params);
    if (result.empty() || result.front().empty()) throw std::runtime_error(sql + ": no row");
    return result.front().front();
  }

  long long integer(const std::string& sql, const std::vector<long long>& params = {}) const {
    return std::stoll(text(sql, params));
  }

 private:
  struct Close {
    void operator()(sqlite3* db) const { sqlite3_close(db); }
  };
  struct Finalize {
    void operator()(sqlite3_stmt* statement) const { sqlite3_finalize(statement); }
  };

  static std::string column(sqlite3_stmt* statement, int c) {
    switch (sqlite3_column_type(statement, c)) {
      case SQLITE_NULL:
        return "NULL";
      case SQLITE_INTEGER:
        return std::to_string(sqlite3_column_int64(statement, c));
      case SQLITE_FLOAT: {
        std::array<char, 32> buffer{};
        const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(),
                                             sqlite3_column_double(statement, c));
        if (ec != std::errc()) throw std::runtime_error("cannot format a real");
        return std::string(buffer.data(), end);
      }
      case SQLITE_BLOB:
        return "blob[" + std::to_string(sqlite3_column_bytes(statement, c)) + "]";
      default: {
        const unsigned char* text = sqlite3_column_text(statement, c);
        const int size = sqlite3_column_bytes(statement, c);
        return std::string(text, text + size);
      }
    }
  }

  std::unique_ptr<sqlite3, Close> db_;
};

}  // namespace pnp::integration
