#include "store/store.h"

namespace pnp::store {

Promotion Store::promote(std::int64_t checkpoint_id, const std::string& by) {
  return promote(std::span<const std::int64_t>(&checkpoint_id, 1), by).front();
}

}  // namespace pnp::store
