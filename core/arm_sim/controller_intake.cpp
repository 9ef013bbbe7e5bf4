#include "arm_sim/controller_intake.h"

#include "common/error.h"

namespace pnp::arm_sim {
namespace {

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

IntakeOutcome take_into_arm(SimulatedArm& arm, const ControllerLimits& limits,
                            const ArmTarget& target) {
  // A non-finite pose is the arm's to refuse (as an invalid target), by name.
  if (auto outside =
          limits.refusal({target.position_m, target.orientation}, arm.state().commanded_base)) {
    return {ControllerStatus::kOutsideLimits, std::move(*outside)};
  }
  const double speed =
      limits.capped_speed(target.max_speed_m_per_s, arm.options().default_max_speed_m_per_s);
  const TargetStatus taken =
      arm.set_target(target.position_m, target.orientation, target.gripper_width_m, speed);
  return {status_of(taken.code), taken.message};
}

}  // namespace pnp::arm_sim
