#pragma once
// Helpers shared by the simulation tests.

#include <memory>

#include "sim/world_model.h"

namespace pnp::sim::testing {

// Compiling a world takes under 10 ms: each test builds its own.
inline std::shared_ptr<const WorldModel> world(Robot robot = Robot::kFetch,
                                               ObjectShape object = ObjectShape::kBlock) {
  return WorldModel::load(robot, object);
}

}  // namespace pnp::sim::testing
