#include "robot/controller_intake.h"

namespace pnp::robot {

IntakeOutcome take_into_arm(ArmBackend& arm, const ControllerLimits& limits,
                            const ArmTarget& target) {
  // A non-finite pose is the arm's to refuse (as an invalid target), by name.
  if (auto outside =
          limits.refusal({target.position_m, target.orientation}, arm.reading().commanded_base)) {
    return {ControllerStatus::kOutsideLimits, std::move(*outside)};
  }
  ArmTarget capped = target;
  capped.max_speed_m_per_s =
      limits.capped_speed(target.max_speed_m_per_s, arm.default_max_speed_m_per_s());
  return arm.command(capped);
}

}  // namespace pnp::robot
