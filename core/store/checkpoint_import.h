#pragma once
// Brings checkpoint files (as pnp-train --out writes them) into a store as finished runs
// of their own, optionally promoting them: how a hierarchy trained elsewhere, or the
// small one checked in for tests, gets served. The file is not interpreted here beyond
// the store's checksum; the inference service verifies its contents when it loads it.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "store/store.h"

namespace pnp::store {

struct CheckpointFile {
  std::string role;       // approach, manipulate, retract, hlc or e2e
  std::string algorithm;  // how it was trained (ddpg_her, a3c, ...)
  std::string robot, object;
  std::filesystem::path path;
};

// Returns the new checkpoint's id. NOT_FOUND when the file cannot be read.
std::int64_t import_checkpoint(Store& store, const CheckpointFile& file, bool promote);

// approach.ckpt, manipulate.ckpt, retract.ckpt and hlc.ckpt from `dir`, promoted, all in
// one transaction: a server reading the store sees the whole hierarchy or none of it.
// Returns the checkpoint ids in that order.
std::vector<std::int64_t> import_hierarchy(Store& store, const std::filesystem::path& dir,
                                           const std::string& robot, const std::string& object);

}  // namespace pnp::store
