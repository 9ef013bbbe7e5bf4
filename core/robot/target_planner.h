#pragma once
// One gateway cycle's decision, without I/O: the policy's action, taken in the simulation
// frame the policy was trained in, becomes the pose target streamed to the arm in its base
// frame. The action is read the way the policy's training world read it
// (sim/world_profile.h), so the arm does what the policy learned an action does:
//   position  `paper`: the commanded grip point (the accumulated mocap target) moves by
//             action_scale_m per unit; `gym`: the measured grip point does (gym resets the
//             mocap target to the gripper before each action). Both are kept inside the
//             simulation's gripper box, as the paper world keeps its target, and inside
//             the gateway's workspace box (its floor keeps the pads off the table, as the
//             table stops the fingers in the gym world).
//   gripper   from the measured opening, by action[3] of the full range (`paper`), or by
//             action[3] metres per finger (`gym`'s ctrl = q + a: effectively open or close).
// The orientation is the episode's (the policy does not turn the gripper), never copied
// back from the controller, which would let it drift. The target is then rate
// limited (libfranka-style) and checked against the safety limits; a refused target must
// not be sent.

#include <optional>

#include "geometry/pose.h"
#include "robot/gateway_config.h"
#include "robot/safety_limits.h"
#include "sim/observation.h"
#include "sim/world_profile.h"

namespace pnp::robot {

struct PlannedTarget {
  PoseTarget base;            // what goes to the controller (base frame)
  geometry::Pose sim;         // the same pose in the simulation frame
  SafetyVerdict verdict;      // refused: hold instead
  bool rate_limited = false;  // the step was shortened to the speed limit
  bool clamped = false;       // the position was brought into the gateway's box
};

// What the controller reports, in its base frame.
struct ArmReading {
  geometry::Pose commanded_base;  // the pose it is driving to
  geometry::Pose measured_base;   // where the grip point is
  double gap_m = 0;               // the measured finger opening
  // What every target of the episode holds: its first commanded orientation.
  Eigen::Quaterniond held_orientation_base = Eigen::Quaterniond::Identity();
};

// INVALID_ARGUMENT for a non-finite reading or held orientation (the controller's own
// report, not the policy's output: a policy NaN becomes a refusal).
PlannedTarget plan_target(const GatewayConfig& config, const sim::WorldParameters& world,
                          const ArmReading& arm, const sim::Action& action);

// What holding sends after a refused plan (or while waiting for the arm): the last
// accepted target again if it still passes the checks from where the arm is commanded
// now; otherwise nothing, and the controller holds by itself.
std::optional<PoseTarget> hold_target(const GatewayConfig& config,
                                      const std::optional<PoseTarget>& last_accepted,
                                      const geometry::Pose& commanded_base);

}  // namespace pnp::robot
