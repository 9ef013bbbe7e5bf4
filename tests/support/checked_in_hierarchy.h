#pragma once
// Puts the checked-in Panda hierarchy (tests/data/panda_block, see its README) into a
// store and promotes it, as a training pipeline would have: what an inference service
// then serves. PNP_TEST_DATA_DIR is set by tests/CMakeLists.txt.

#include <filesystem>

#include "store/checkpoint_import.h"

namespace pnp::testing {

inline void promote_checked_in_panda_hierarchy(store::Store& store) {
  store::import_hierarchy(store, std::filesystem::path(PNP_TEST_DATA_DIR) / "panda_block", "panda",
                          "block");
}

}  // namespace pnp::testing
