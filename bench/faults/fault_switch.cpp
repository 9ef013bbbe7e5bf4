#include "bench/faults/fault_switch.h"

namespace pnp::faults {

std::optional<CallSite> call_site(FaultKind kind) {
  switch (kind) {
    case FaultKind::kControllerStall:
    case FaultKind::kBrokenReading:
      return CallSite::kGetState;
    case FaultKind::kInferenceStall:
      return CallSite::kPredict;
    case FaultKind::kDroppedStream:
    case FaultKind::kEmergencyStop:
      return CallSite::kTarget;
    case FaultKind::kMiscalibratedGateway:
      return std::nullopt;
  }
  return std::nullopt;
}

void FaultSwitch::arm(std::optional<PlannedFault> fault) {
  const std::lock_guard lock(mutex_);
  armed_ = fault;
  for (int& c : counts_) c = 0;
  fired_.reset();
}

std::optional<FaultKind> FaultSwitch::fire(CallSite site) {
  const std::lock_guard lock(mutex_);
  const int count = ++counts_[static_cast<int>(site)];
  if (!armed_ || call_site(armed_->kind) != site || fired_ || count != armed_->at_call) {
    return std::nullopt;
  }
  fired_ = Clock::now();
  return armed_->kind;
}

std::optional<FaultSwitch::Clock::time_point> FaultSwitch::fired_at() const {
  const std::lock_guard lock(mutex_);
  return fired_;
}

void FaultSwitch::set_policy_dives(bool dives) {
  const std::lock_guard lock(mutex_);
  policy_dives_ = dives;
}

bool FaultSwitch::policy_dives() const {
  const std::lock_guard lock(mutex_);
  return policy_dives_;
}

void FaultSwitch::stall_controller_until(Clock::time_point until) {
  const std::lock_guard lock(mutex_);
  stalled_until_ = until;
}

FaultSwitch::Clock::time_point FaultSwitch::controller_stalled_until() const {
  const std::lock_guard lock(mutex_);
  return stalled_until_;
}

}  // namespace pnp::faults
