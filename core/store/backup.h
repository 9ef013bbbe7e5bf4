#pragma once
// A consistent copy of a live store (SQLite's online backup API): what `pnpctl backup`
// and the store service's Backup write. The copy is one snapshot of the database, taken
// while servers keep training and serving (in WAL mode a reader never blocks a writer),
// written beside the destination and renamed into place only once it is whole and passes
// SQLite's integrity check: a failed or interrupted backup never leaves a file that looks
// like a store. A backup file is itself a store: restoring is opening it (`--db FILE`).

#include <cstdint>
#include <string>

namespace pnp::store {

struct BackupReport {
  std::string path;        // the destination
  std::int64_t bytes = 0;  // its size
  std::int64_t runs = 0;   // runs in the copy
  std::int64_t checkpoints = 0;
};

// Copies the store at `source` (an existing file) into `destination`, which must not exist
// (FAILED_PRECONDITION naming it: a backup never overwrites). NOT_FOUND if `source` does
// not exist; DATA_LOSS if the copy fails its integrity check.
BackupReport backup_store(const std::string& source, const std::string& destination);

}  // namespace pnp::store
