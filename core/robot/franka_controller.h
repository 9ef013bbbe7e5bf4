#pragma once
// What pnp-franka-bridge serves: a Franka (FrankaBackend) behind the controller's rules
// (ArmController). The ROS side hands each message in through these methods, and its
// streaming loop calls tick(); each runs under the controller's lock and publishes the
// state, so a reflex or a stall is a stop the moment it is seen.

#include "robot/arm_controller.h"
#include "robot/franka_backend.h"

namespace pnp::robot {

namespace detail {
// The backend, built before the controller that drives it (a base listed first is
// constructed first).
struct FrankaBackendHolder {
  FrankaBackendHolder(FrankaCommands& commands, const FrankaBackendOptions& options)
      : backend(commands, options) {}
  FrankaBackend backend;
};
}  // namespace detail

class FrankaController : private detail::FrankaBackendHolder, public ArmController {
 public:
  // `commands` must outlive the controller. INVALID_ARGUMENT for options out of range.
  FrankaController(FrankaCommands& commands, const FrankaBackendOptions& backend_options,
                   ArmControllerOptions controller_options)
      : FrankaBackendHolder(commands, backend_options),
        ArmController(backend, std::move(controller_options)) {}

  void on_state(const FrankaStateSample& sample) {
    run_tick([&] { backend.on_state(sample); });
  }
  void on_gripper_width(double width_m) {
    run_tick([&] { backend.on_gripper_width(width_m); });
  }
  void on_object(const TrackedObject& object) {
    run_tick([&] { backend.on_object(object); });
  }
  void tick(SteadyTime now, double dt_s) {
    run_tick([&] { backend.tick(now, dt_s); });
  }
};

}  // namespace pnp::robot
