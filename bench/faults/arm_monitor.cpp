#include "bench/faults/arm_monitor.h"

#include <algorithm>

namespace pnp::faults {
namespace {

bool at_rest(arm_sim::ArmMode mode) {
  return mode == arm_sim::ArmMode::kHolding || mode == arm_sim::ArmMode::kStopped ||
         mode == arm_sim::ArmMode::kIdle;
}

}  // namespace

ArmMonitor::ArmMonitor(const arm_sim::ControllerStandIn& arm)
    : arm_(arm), watcher_([this](const std::stop_token& stop) { watch(stop); }) {}

ArmMonitor::~ArmMonitor() {
  watcher_.request_stop();
}

void ArmMonitor::watch(const std::stop_token& stop) {
  std::uint64_t last_sequence = 0;
  auto next = Clock::now();
  while (!stop.stop_requested()) {
    const robot::ControllerReport report = arm_.state();
    Sample sample{Clock::now(), report.arm.mode, report.sequence, report.arm.target_base.position_m,
                  report.arm.tcp_base.position_m.z()};
    {
      const std::lock_guard lock(mutex_);
      if (report.sequence != last_sequence && report.sequence > 0) taken_.push_back(sample);
      samples_.push_back(sample);
      lowest_grip_z_m_ = std::min(lowest_grip_z_m_, sample.grip_z_base_m);
    }
    last_sequence = report.sequence;
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
}

int ArmMonitor::taken_outside(const robot::WorkspaceBox& box) const {
  const std::lock_guard lock(mutex_);
  return static_cast<int>(std::count_if(
      taken_.begin(), taken_.end(), [&](const Sample& s) { return !box.contains(s.target_base); }));
}

int ArmMonitor::targets_taken() const {
  const std::lock_guard lock(mutex_);
  return static_cast<int>(taken_.size());
}

double ArmMonitor::lowest_grip_z_m() const {
  const std::lock_guard lock(mutex_);
  return lowest_grip_z_m_;
}

ArmMonitor::AfterFault ArmMonitor::after_fault(Clock::time_point fault,
                                               Clock::time_point until) const {
  const std::lock_guard lock(mutex_);
  AfterFault after;
  for (const Sample& s : taken_) {
    if (s.time >= fault && s.time < until) after.last_taken = s.time;
  }
  const Clock::time_point from = after.last_taken ? std::max(fault, *after.last_taken) : fault;
  const auto first =
      std::lower_bound(samples_.begin(), samples_.end(), from,
                       [](const Sample& s, Clock::time_point t) { return s.time < t; });
  for (auto it = first; it != samples_.end() && it->time < until; ++it) {
    if (at_rest(it->mode)) {
      after.held_at = it->time;
      break;
    }
  }
  return after;
}

}  // namespace pnp::faults
