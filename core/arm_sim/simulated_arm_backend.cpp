#include "arm_sim/simulated_arm_backend.h"

#include "common/error.h"

namespace pnp::arm_sim {
namespace {

using robot::ControllerStatus;

ControllerStatus status_of(TargetCode code) {
  switch (code) {
    case TargetCode::kAccepted:
      return ControllerStatus::kOk;
    case TargetCode::kInvalid:
      return ControllerStatus::kInvalidTarget;
    case TargetCode::kUnreachable:
      return ControllerStatus::kUnreachable;
    case TargetCode::kJointLimit:
      return ControllerStatus::kJointLimit;
    case TargetCode::kStopped:
      return ControllerStatus::kStopped;
  }
  throw_internal("unknown target code");
}

}  // namespace

robot::BackendReading reading_of(const ArmState& state) {
  robot::BackendReading reading;
  reading.mode = state.mode;
  reading.tcp_base = state.tcp_base;
  reading.commanded_base = state.commanded_base;
  reading.setpoint_base = state.setpoint_base;
  reading.target_base = state.target_base;
  reading.finger_gap_m = state.finger_gap_m;
  reading.joint_positions_rad = state.joint_positions;
  reading.object_base = state.object_base;
  if (state.mode == ArmMode::kFault)
    reading.fault = "the simulation became unstable (reset the scene)";
  return reading;
}

robot::IntakeOutcome SimulatedArmBackend::command(const robot::ArmTarget& target) {
  const TargetStatus taken = arm_.set_target(target.position_m, target.orientation,
                                             target.gripper_width_m, target.max_speed_m_per_s);
  return {status_of(taken.code), taken.message};
}

void SimulatedArmBackend::after_target() {
  if (clock_ == ClockMode::kLockstep) arm_.advance(arm_.options().policy_period_s);
}

}  // namespace pnp::arm_sim
