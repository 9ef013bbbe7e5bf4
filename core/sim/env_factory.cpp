#include "sim/env_factory.h"

#include "common/error.h"
#include "sim/pick_place_env.h"

namespace pnp::sim {

LocalEnvFactory::LocalEnvFactory(std::shared_ptr<const WorldModel> world)
    : world_(std::move(world)) {
  if (!world_) throw Error(ErrorCode::kInvalidArgument, "world: expected a loaded world, got none");
}

std::unique_ptr<Environment> LocalEnvFactory::make() const {
  return std::make_unique<PickPlaceEnv>(world_);
}

}  // namespace pnp::sim
