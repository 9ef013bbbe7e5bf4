#include "arm_sim/controller_stand_in.h"

#include <chrono>

#include "sim/panda_hand.h"

namespace pnp::arm_sim {
namespace {

robot::ArmControllerOptions controller_options(const StandInOptions& options) {
  robot::ArmControllerOptions controller;
  controller.base_frame_id = options.base_frame_id;
  controller.default_lease_timeout_s = options.default_lease_timeout_s;
  controller.max_lease_timeout_s = options.max_lease_timeout_s;
  controller.limits = options.limits;
  controller.lockstep = options.clock == ClockMode::kLockstep;
  controller.tcp_from_flange_m = sim::kGripPointFromFlange_m;
  return controller;
}

}  // namespace

detail::SimulatedArmHolder::SimulatedArmHolder(const StandInOptions& options)
    : arm(sim::Robot::kPanda, options.object, options.world, options.arm),
      backend(arm, options.clock) {}

ControllerStandIn::ControllerStandIn(const StandInOptions& options)
    : SimulatedArmHolder(options),
      ArmController(backend, controller_options(options)),
      clock_(options.clock) {
  if (clock_ == ClockMode::kRealTime) {
    clock_thread_ = std::jthread([this](const std::stop_token& stop) { run_real_time(stop); });
  }
}

ControllerStandIn::~ControllerStandIn() = default;

// The arm's own loop: one control tick per millisecond of steady-clock time. When the
// process is descheduled the ticks it owes run back to back (at most 20, then the
// schedule restarts from now), so simulated time tracks wall time.
void ControllerStandIn::run_real_time(const std::stop_token& stop) {
  using Clock = std::chrono::steady_clock;
  constexpr auto kTick = std::chrono::microseconds(1000);
  constexpr int kMaxCatchUp = 20;
  auto next = Clock::now() + kTick;
  while (!stop.stop_requested()) {
    std::this_thread::sleep_until(next);
    int owed = 0;
    const auto now = Clock::now();
    while (next <= now && owed < kMaxCatchUp) {
      next += kTick;
      ++owed;
    }
    if (owed == kMaxCatchUp) next = now + kTick;
    // One tick per lock: a target or a state read waits at most one tick (~0.1 ms).
    for (int k = 0; k < owed; ++k) run_tick([this] { arm.advance(kControlPeriod_s); });
  }
}

ControllerStandIn::SceneReset ControllerStandIn::reset_scene(const std::string& lease_id,
                                                             std::uint64_t seed) {
  return placed(lease_id, [&] { return arm.reset(seed); });
}

ControllerStandIn::SceneReset ControllerStandIn::reset_scene_to(const std::string& lease_id,
                                                                const ObservedScene& scene) {
  return placed(lease_id, [&] { return arm.reset_to(scene); });
}

ControllerStandIn::SceneReset ControllerStandIn::placed(const std::string& lease_id,
                                                        const std::function<Episode()>& place) {
  const CallerLock lock(*this);
  require_lease(lease_id, robot::LeaseBook::Clock::now());
  require_not_stopped("resetting the scene");
  const Episode episode = place();
  publish_locked();
  return {report_locked(robot::ControllerStatus::kOk, {}), episode.goal_base};
}

}  // namespace pnp::arm_sim
