#pragma once
// Where the environments of a training run or an evaluation come from: each worker
// makes its own, on its own thread, so make() must be safe to call concurrently. The
// factory also says which world they simulate, for what depends on it (object width).

#include <memory>

#include "sim/actuation.h"
#include "sim/environment.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_model.h"

namespace pnp::sim {

class EnvFactory {
 public:
  virtual ~EnvFactory() = default;
  virtual std::unique_ptr<Environment> make() const = 0;
  virtual Robot robot() const = 0;
  virtual ObjectShape object() const = 0;
  virtual WorldProfile profile() const = 0;
  virtual Actuation actuation() const = 0;
  // The extent the fingers close on, metres (what task states carry).
  double object_width_m() const { return 2 * object_spec(object()).half_width_m; }

 protected:
  EnvFactory() = default;
  EnvFactory(const EnvFactory&) = default;
  EnvFactory& operator=(const EnvFactory&) = default;
};

// Environments in this process, sharing one loaded world, their hands on gym's mocap
// (arm_sim/arm_env_factory.h makes arm-actuated ones).
class LocalEnvFactory final : public EnvFactory {
 public:
  explicit LocalEnvFactory(std::shared_ptr<const WorldModel> world);
  std::unique_ptr<Environment> make() const override;
  Robot robot() const override { return world_->robot(); }
  ObjectShape object() const override { return world_->object(); }
  WorldProfile profile() const override { return world_->profile(); }
  Actuation actuation() const override { return Actuation::kMocap; }
  const std::shared_ptr<const WorldModel>& world() const { return world_; }

 private:
  std::shared_ptr<const WorldModel> world_;
};

}  // namespace pnp::sim
