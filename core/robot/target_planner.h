#pragma once
// One gateway cycle's decision, without I/O: the policy's action, taken in the simulation
// frame the policy was trained in, becomes the pose target streamed to the arm in its base
// frame. The action moves the commanded grip point (the mocap target in training) by
// action_scale_m per unit on each axis, kept inside the simulation's gripper box as the
// environment keeps it; the gripper opens or closes by action[3] of its full range from
// the measured opening, as the environment's finger servos do. The orientation is held:
// the policy does not turn the gripper. The target is then rate limited (libfranka-style)
// and checked against the safety limits; a refused target must not be sent.

#include "geometry/pose.h"
#include "robot/gateway_config.h"
#include "robot/safety_limits.h"
#include "sim/observation.h"

namespace pnp::robot {

struct PlannedTarget {
  PoseTarget base;            // what goes to the controller (base frame)
  geometry::Pose sim;         // the same pose in the simulation frame
  SafetyVerdict verdict;      // refused: hold instead
  bool rate_limited = false;  // the step was shortened to the speed limit
};

// `commanded_base`: the controller's current commanded pose; `measured_gap_m`: the
// measured finger opening. INVALID_ARGUMENT for a non-finite commanded pose or gap (the
// controller's own report, not the policy's output: a policy NaN becomes a refusal).
PlannedTarget plan_target(const GatewayConfig& config, const geometry::Pose& commanded_base,
                          double measured_gap_m, const sim::Action& action);

}  // namespace pnp::robot
