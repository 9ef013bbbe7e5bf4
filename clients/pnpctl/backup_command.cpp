// backup: a consistent copy of the store, taken while the servers keep training and
// serving: from the store file itself (--db) or through pnp-store-server (--store). The
// copy is a store file; restoring is starting the servers (or the store server) on it.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "clients/pnpctl/commands.h"
#include "common/error.h"
#include "services/store/remote_store.h"
#include "store/run_store.h"

namespace pnp::pnpctl {

int backup_command(const BackupArgs& args) {
  if (args.db.empty() != args.store.remote())
    throw_invalid_argument("--db", "a store file, or --store host:port", "neither or both");
  std::unique_ptr<store::Store> source;
  if (args.store.remote()) {
    source = services::remote_store_opener(args.store.address, args.store.tls)();
  } else {
    // Never a new, empty store for a mistyped path.
    if (!std::filesystem::is_regular_file(args.db))
      throw_invalid_argument("--db", "an existing store file",
                             "\"" + args.db + "\" (no such file)");
    source = std::make_unique<store::RunStore>(args.db);
  }
  const store::BackupReport report = source->backup(args.destination);
  if (args.json) {
    std::printf("%s\n", nlohmann::json{{"backup", report.path},
                                       {"bytes", report.bytes},
                                       {"runs", report.runs},
                                       {"checkpoints", report.checkpoints}}
                            .dump()
                            .c_str());
    return 0;
  }
  std::printf("%s: %lld runs and %lld checkpoints, %.1f MB (serve it with --db %s)\n",
              report.path.c_str(), static_cast<long long>(report.runs),
              static_cast<long long>(report.checkpoints), static_cast<double>(report.bytes) / 1e6,
              report.path.c_str());
  return 0;
}

}  // namespace pnp::pnpctl
