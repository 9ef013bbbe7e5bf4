#pragma once
// Compiled worlds by robot, object and profile, each loaded once and then shared. Loading
// compiles the MJCF and solves the home pose: tens of milliseconds and a transient mjData
// of several MB. A server that opens environments all day (the simulation service) would
// otherwise pay both on every request, and the churn of those large blocks is what made
// its resident memory creep (docs/RELIABILITY.md, "Soak"). A WorldModel is immutable, so
// every environment of a key can share it. The cache holds at most one world per key: a
// few dozen at most.

#include <map>
#include <memory>
#include <mutex>
#include <tuple>

#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_model.h"
#include "sim/world_profile.h"

namespace pnp::sim {

class WorldCache {
 public:
  // The world for the key, loaded on first use (outside the lock: loads of other keys go
  // on meanwhile). Throws what WorldModel::load throws; a failed load is not cached.
  std::shared_ptr<const WorldModel> get(Robot robot, ObjectShape object, WorldProfile profile);
  // Worlds loaded so far.
  std::size_t size() const;

 private:
  using Key = std::tuple<Robot, ObjectShape, WorldProfile>;
  mutable std::mutex mutex_;
  std::map<Key, std::shared_ptr<const WorldModel>> worlds_;
};

}  // namespace pnp::sim
