#pragma once
// Where environments come from for a world chosen by robot, object, profile and actuation:
// mocap worlds are sim::LocalEnvFactory's, arm-actuated ones this file's. Every tool and
// service that makes in-process environments from a spec goes through make_env_factory,
// so a new actuation is added here once.

#include <memory>

#include "arm_sim/arm_actuated_env.h"
#include "sim/env_factory.h"

namespace pnp::arm_sim {

// Arm-actuated environments in this process, sharing one loaded Panda world.
class ArmEnvFactory final : public sim::EnvFactory {
 public:
  // INVALID_ARGUMENT unless `world` is a loaded Panda world.
  explicit ArmEnvFactory(std::shared_ptr<const sim::WorldModel> world,
                         const ArmWorldOptions& options = {});
  std::unique_ptr<sim::Environment> make() const override;
  sim::Robot robot() const override { return world_->robot(); }
  sim::ObjectShape object() const override { return world_->object(); }
  sim::WorldProfile profile() const override { return world_->profile(); }
  sim::Actuation actuation() const override { return sim::Actuation::kArm; }

 private:
  std::shared_ptr<const sim::WorldModel> world_;
  ArmWorldOptions options_;
};

// The factory for a world: INVALID_ARGUMENT naming "actuation" for an arm-actuated robot
// other than the Panda (sim::require_supported).
std::unique_ptr<sim::EnvFactory> make_env_factory(sim::Robot robot, sim::ObjectShape object,
                                                  sim::WorldProfile profile,
                                                  sim::Actuation actuation);
// The same over a world already loaded (a sim::WorldCache's, say).
std::unique_ptr<sim::EnvFactory> make_env_factory(std::shared_ptr<const sim::WorldModel> world,
                                                  sim::Actuation actuation);

}  // namespace pnp::arm_sim
