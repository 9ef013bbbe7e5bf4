#include "services/common/store_path.h"

#include <cstdlib>
#include <filesystem>

#include "common/error.h"

namespace pnp::services {

std::string resolve_store_path(const std::string& flag, bool must_exist) {
  std::string path = flag;
  if (path.empty()) {
    const char* env = std::getenv("PNP_DB");
    if (env != nullptr) path = env;
  }
  if (path.empty()) throw_invalid_argument("--db", "a store file (or $PNP_DB)", "neither");
  if (must_exist && !std::filesystem::exists(path)) {
    throw_invalid_argument("--db",
                           "an existing store (a training server creates one; --create-db starts "
                           "an empty one)",
                           "no file " + path);
  }
  return path;
}

}  // namespace pnp::services
