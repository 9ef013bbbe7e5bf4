#pragma once
// Watches the controller stand-in from the arm's side at its 1 kHz tick: every target it
// takes in (where it was), its mode, and the lowest the grip point went. This is the
// benchmark's ground truth, independent of what the gateway reports: whether a target
// outside the controller's box was ever executed, and how long after a fault the arm was
// holding or stopped with nothing new taken in.

#include <Eigen/Core>
#include <chrono>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "arm_sim/controller_stand_in.h"
#include "robot/safety_limits.h"

namespace pnp::faults {

class ArmMonitor {
 public:
  using Clock = std::chrono::steady_clock;

  struct Sample {
    Clock::time_point time;
    arm_sim::ArmMode mode = arm_sim::ArmMode::kIdle;
    std::uint64_t sequence = 0;
    Eigen::Vector3d target_base = Eigen::Vector3d::Zero();  // the latest accepted target
    double grip_z_base_m = 0;                               // measured
  };

  // What the arm did after a fault at `fault`, up to `until`.
  struct AfterFault {
    std::optional<Clock::time_point> last_taken;  // the last target taken in, if any
    std::optional<Clock::time_point> held_at;     // holding or stopped with nothing after
  };

  explicit ArmMonitor(const arm_sim::ControllerStandIn& arm);
  ~ArmMonitor();  // stops watching
  ArmMonitor(const ArmMonitor&) = delete;
  ArmMonitor& operator=(const ArmMonitor&) = delete;

  // Targets taken in whose position lies outside `box` (base frame), over the whole run.
  int taken_outside(const robot::WorkspaceBox& box) const;
  int targets_taken() const;
  double lowest_grip_z_m() const;
  AfterFault after_fault(Clock::time_point fault, Clock::time_point until) const;

 private:
  void watch(const std::stop_token& stop);

  const arm_sim::ControllerStandIn& arm_;
  mutable std::mutex mutex_;
  std::vector<Sample> taken_;     // one per target taken in; guarded by mutex_
  std::vector<Sample> samples_;   // every tick; guarded by mutex_
  double lowest_grip_z_m_ = 1e9;  // guarded by mutex_
  std::jthread watcher_;          // last: stopped and joined first
};

}  // namespace pnp::faults
