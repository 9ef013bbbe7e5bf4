// gc: retention over the store file itself (the one command that opens it directly, as a
// maintenance tool beside the servers; they keep training and serving meanwhile, waiting
// out its short write transaction).
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "clients/pnpctl/commands.h"
#include "common/error.h"
#include "store/run_store.h"

namespace pnp::pnpctl {

int gc_command(const std::string& db_path, int keep_last, bool json) {
  // Never a new, empty store for a mistyped path.
  if (!std::filesystem::is_regular_file(db_path))
    throw_invalid_argument("--db", "an existing store file", "\"" + db_path + "\" (no such file)");
  store::RunStore store(db_path);
  const store::GcReport report = store.collect_garbage({.keep_last = keep_last});
  if (json) {
    std::printf("%s\n", nlohmann::json{{"db", db_path},
                                       {"keep_last", keep_last},
                                       {"checkpoints_deleted", report.checkpoints_deleted},
                                       {"bytes_deleted", report.bytes_deleted},
                                       {"pages_freed", report.pages_freed}}
                            .dump()
                            .c_str());
    return 0;
  }
  std::printf(
      "%s: deleted %lld checkpoints (%.1f MB of weights), gave %lld pages back to the "
      "filesystem; kept the last %d of every run with its best, promoted and referenced ones\n",
      db_path.c_str(), static_cast<long long>(report.checkpoints_deleted),
      static_cast<double>(report.bytes_deleted) / 1e6, static_cast<long long>(report.pages_freed),
      keep_last);
  return 0;
}

}  // namespace pnp::pnpctl
