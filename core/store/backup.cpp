#include "store/backup.h"

#include <sqlite3.h>

#include <filesystem>
#include <memory>

#include "common/error.h"
#include "store/sqlite.h"

namespace pnp::store {
namespace {

struct FinishBackup {
  void operator()(sqlite3_backup* b) const { sqlite3_backup_finish(b); }
};

// The whole database in one step: the source's read transaction is one snapshot, and in
// WAL mode it never blocks the servers' writes.
void copy_pages(Database& from, Database& to) {
  std::unique_ptr<sqlite3_backup, FinishBackup> backup(
      sqlite3_backup_init(to.handle(), "main", from.handle(), "main"));
  if (!backup) {
    throw Error(ErrorCode::kInternal,
                "backup of " + from.path() + ": " + sqlite3_errmsg(to.handle()));
  }
  int rc = SQLITE_OK;
  for (int attempt = 0; attempt < 200; ++attempt) {
    rc = sqlite3_backup_step(backup.get(), -1);
    if (rc != SQLITE_BUSY && rc != SQLITE_LOCKED) break;
    sqlite3_sleep(25);  // a writer holds a lock the snapshot needs: wait it out
  }
  const int finished = sqlite3_backup_finish(backup.release());
  if (rc != SQLITE_DONE || finished != SQLITE_OK) {
    throw Error(
        rc == SQLITE_BUSY || rc == SQLITE_LOCKED ? ErrorCode::kUnavailable : ErrorCode::kInternal,
        "backup of " + from.path() + ": " + sqlite3_errstr(rc));
  }
}

}  // namespace

BackupReport backup_store(const std::string& source, const std::string& destination) {
  if (!std::filesystem::is_regular_file(source))
    throw_invalid_argument("store", "an existing store file", "\"" + source + "\" (no such file)");
  if (std::filesystem::exists(destination)) {
    throw Error(ErrorCode::kFailedPrecondition,
                "backup: " + destination + " already exists (a backup never overwrites a file)");
  }
  const std::string partial = destination + ".partial";
  std::filesystem::remove(partial);
  BackupReport report{destination};
  try {
    {
      Database from(source, {.access = Access::kReadOnly});
      Database to(partial);
      copy_pages(from, to);
      const bool whole = [&] {
        auto check = to.prepare("PRAGMA integrity_check");
        return check.step() && check.column_text(0) == "ok";
      }();
      if (!whole) {
        throw Error(ErrorCode::kDataLoss,
                    "backup of " + source + ": the copy failed its integrity check");
      }
      const auto count = [&](std::string_view table) {
        auto st = to.prepare("SELECT COUNT(*) FROM " + std::string(table));
        st.step();
        return st.column_int(0);
      };
      report.runs = count("runs");
      report.checkpoints = count("checkpoints");
      to.execute("PRAGMA wal_checkpoint(TRUNCATE)");  // the copy is one self-contained file
      to.execute("PRAGMA journal_mode = DELETE");
    }
    std::filesystem::rename(partial, destination);
  } catch (...) {
    for (const char* suffix : {"", "-wal", "-shm", "-journal"})
      std::filesystem::remove(partial + suffix);
    throw;
  }
  report.bytes = static_cast<std::int64_t>(std::filesystem::file_size(destination));
  return report;
}

}  // namespace pnp::store
