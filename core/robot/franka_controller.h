#pragma once
// What pnp-franka-bridge serves: a Franka (FrankaBackend) behind the controller's rules
// (ArmController). The ROS side hands each message in through these methods, and its
// streaming loop calls tick(); each runs under the controller's lock and publishes the
// state, so a reflex or a stall is a stop the moment it is seen.

#include <chrono>
#include <string>
#include <thread>
#include <utility>

#include "common/error.h"
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

  // A simulated arm's scene reset, done by `reset` (which moves the arm elsewhere): the
  // lease is checked first (FAILED_PRECONDITION), then, once a state measured after the
  // reset has arrived (UNAVAILABLE if none within `state_wait_s`), the bridge holds where
  // the arm now is. With a tracker, its first pose after the reset is waited for too
  // (within the same time; after that the object is reported as the tracker left it, and
  // a stale pose as none), so nobody reads the scene before it as the one after it.
  // Returns what `reset` returned and the controller's report.
  template <typename Reset>
  auto reset_scene(const std::string& lease_id, Reset&& reset, double state_wait_s = 1.0) {
    bool tracked = false;
    {
      const CallerLock lock(*this);
      require_lease(lease_id, LeaseBook::Clock::now());
      require_not_stopped("resetting the scene");
      backend.pause_streaming();
      tracked = backend.last_object_received().has_value();
    }
    auto result = [&] {
      try {
        return reset();
      } catch (...) {  // the arm did not move: stream its set point again
        const CallerLock lock(*this);
        backend.rest_at_measured();
        throw;
      }
    }();
    const SteadyTime done = std::chrono::steady_clock::now();
    const SteadyTime deadline = done + std::chrono::duration_cast<SteadyTime::duration>(
                                           std::chrono::duration<double>(state_wait_s));
    while (true) {
      {
        const CallerLock lock(*this);
        const auto received = backend.last_state_received();
        const auto seen = backend.last_object_received();
        const bool object_fresh = !tracked || (seen && *seen > done);
        if (received && *received > done &&
            (object_fresh || std::chrono::steady_clock::now() > deadline)) {
          backend.rest_at_measured();
          publish_locked();
          return std::pair{std::move(result), report_locked(ControllerStatus::kOk, {})};
        }
      }
      if (std::chrono::steady_clock::now() > deadline) {
        const CallerLock lock(*this);
        backend.rest_at_measured();
        throw Error(ErrorCode::kUnavailable, "no FrankaState after the scene reset within " +
                                                 std::to_string(state_wait_s) + " s");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
};

}  // namespace pnp::robot
