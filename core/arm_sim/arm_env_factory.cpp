#include "arm_sim/arm_env_factory.h"

#include <string>

#include "common/error.h"

namespace pnp::arm_sim {

ArmEnvFactory::ArmEnvFactory(std::shared_ptr<const sim::WorldModel> world,
                             const ArmWorldOptions& options)
    : world_(std::move(world)), options_(options) {
  if (!world_) throw_invalid_argument("world", "a loaded world", "none");
  sim::require_supported(world_->robot(), sim::Actuation::kArm);
}

std::unique_ptr<sim::Environment> ArmEnvFactory::make() const {
  return std::make_unique<ArmActuatedEnv>(world_, options_);
}

std::unique_ptr<sim::EnvFactory> make_env_factory(sim::Robot robot, sim::ObjectShape object,
                                                  sim::WorldProfile profile,
                                                  sim::Actuation actuation) {
  sim::require_supported(robot, actuation);  // before compiling a world nothing can drive
  return make_env_factory(sim::WorldModel::load(robot, object, profile), actuation);
}

std::unique_ptr<sim::EnvFactory> make_env_factory(std::shared_ptr<const sim::WorldModel> world,
                                                  sim::Actuation actuation) {
  if (!world) throw_invalid_argument("world", "a loaded world", "none");
  sim::require_supported(world->robot(), actuation);
  switch (actuation) {
    case sim::Actuation::kMocap:
      return std::make_unique<sim::LocalEnvFactory>(std::move(world));
    case sim::Actuation::kArm:
      return std::make_unique<ArmEnvFactory>(std::move(world));
  }
  throw_internal("make_env_factory: unknown Actuation value");
}

}  // namespace pnp::arm_sim
