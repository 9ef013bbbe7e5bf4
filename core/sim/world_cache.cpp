#include "sim/world_cache.h"

namespace pnp::sim {

std::shared_ptr<const WorldModel> WorldCache::get(Robot robot, ObjectShape object,
                                                  WorldProfile profile) {
  const Key key{robot, object, profile};
  {
    std::lock_guard lock(mutex_);
    if (const auto it = worlds_.find(key); it != worlds_.end()) return it->second;
  }
  auto loaded = WorldModel::load(robot, object, profile);
  std::lock_guard lock(mutex_);
  // Two first requests may both load; the first stored wins, so every caller shares one.
  return worlds_.try_emplace(key, std::move(loaded)).first->second;
}

std::size_t WorldCache::size() const {
  std::lock_guard lock(mutex_);
  return worlds_.size();
}

}  // namespace pnp::sim
