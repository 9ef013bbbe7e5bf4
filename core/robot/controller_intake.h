#pragma once
// What the arm's controller does with a target once its network side has taken it (the
// lease, the stream's sequence, the frame and the stamp checked): its own limits
// (controller_limits.h) first, then the arm's own refusals (reach, joint limits, a stop).
// Every controller (pnp-robot-sim, pnp-franka-bridge) and the arm-actuated training world
// take targets through this one function, so a policy meets in training exactly the
// refusals it meets on the controller.

#include "robot/arm_backend.h"
#include "robot/controller_limits.h"

namespace pnp::robot {

// Refusals change nothing on the arm; an accepted target starts the arm's next segment.
IntakeOutcome take_into_arm(ArmBackend& arm, const ControllerLimits& limits,
                            const ArmTarget& target);

}  // namespace pnp::robot
