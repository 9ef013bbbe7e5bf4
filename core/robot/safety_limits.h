#pragma once
// The last check a pose target passes on the gateway before it is streamed to the arm's
// controller: finite, a unit quaternion, inside the workspace, and a small enough move
// from the previous command. The controller enforces its own limits as well (it never
// trusts the network side); this check makes a bad policy output a refusal with a reason
// at the gateway instead of a fault at the arm.
//
// Everything is in the robot's base frame (panda_link0): positions in metres, the
// position being the grip point between the fingertips.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>

#include "geometry/pose.h"

namespace pnp::robot {

// An axis-aligned box in the base frame.
struct WorkspaceBox {
  Eigen::Vector3d min_m;
  Eigen::Vector3d max_m;
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min_m.array()).all() && (p.array() <= max_m.array()).all();
  }
};

// The Panda's reach (Franka's datasheet: 855 mm from the shoulder, joint 2, which sits
// 0.333 m above the base): a box corner beyond it is a typo, not a workspace.
inline constexpr double kPandaReach_m = 0.855;
inline constexpr double kPandaShoulderHeight_m = 0.333;

// INVALID_ARGUMENT naming `<prefix>.workspace.min_m[i]` (or max_m, or `<prefix>.table_top_z_m`)
// for a box that is not finite, has min >= max on an axis, lets the finger pads within
// sim::kPadClearance_m of the table (a floor below sim::lowest_grip_point_z), or reaches
// beyond the Panda's reach (kPandaReach_m horizontally from the base axis, or above the
// shoulder plus the reach).
void validate_workspace(const WorkspaceBox& box, double table_top_z_m, std::string_view prefix);

// Defaults for a Franka Panda driven at the policy's 25 Hz (0.04 s per cycle).
struct SafetyLimits {
  // The simulated task's gripper box (sim/world_layout.h kWorkspaceMin/Max, world x
  // 1.05..1.55, y 0.40..1.10, z 0.405..0.85) widened by 3 cm in x, y and upwards, seen
  // from the simulated Panda's panda_link0 at world (0.88, 0.75, 0.40) with axes aligned
  // to the world; its floor is the lowest grip point that keeps the pads 2 mm above the
  // table (sim::lowest_grip_point_z(0) = 12.1 mm, rounded up).
  WorkspaceBox workspace{{0.14, -0.38, 0.013}, {0.70, 0.38, 0.48}};
  // The table top's height in the base frame (the simulated table: world z 0.40, the
  // base's height).
  double table_top_z_m = 0.0;
  // A policy action moves at most 0.05 m per axis (0.087 m diagonally) per cycle; more
  // than 0.1 m between consecutive commands is not a policy step.
  double max_step_m = 0.1;
  // The Panda's Cartesian translation velocity limit (Franka's datasheet: 1.7 m/s).
  double max_speed_m_per_s = 1.7;
  // The policy never turns the gripper (its action is xyz and the fingers), so any
  // rotation between commands is a fault; 0.2 rad per cycle (5 rad/s, twice the Panda's
  // 2.5 rad/s Cartesian rotation limit, which the controller enforces) catches a flip.
  double max_rotation_step_rad = 0.2;
  // The Franka Hand opens from 0 to 0.08 m between the fingers.
  double gripper_min_width_m = 0.0;
  double gripper_max_width_m = 0.08;
  // | |q| - 1 | allowed for a target's orientation (as the controller's own check).
  double quaternion_norm_tolerance = 1e-3;

  // INVALID_ARGUMENT naming the field (as `limits.<field>`) for a non-finite or
  // non-positive limit, a box validate_workspace refuses, or a gripper range with
  // min >= max or min < 0.
  void validate() const;
};

struct PoseTarget {
  geometry::Pose pose;
  double gripper_width_m = 0;
};

// Why a target was refused, in the order check_target tests them.
enum class SafetyRefusal {
  kNonFinite,
  kBadQuaternion,
  kOutsideWorkspace,
  kStepTooLarge,
  kTooFast,
  kRotationStepTooLarge,
  kGripperOutOfRange,
};

std::string_view safety_refusal_name(SafetyRefusal refusal);  // e.g. "outside_workspace"

struct SafetyVerdict {
  std::optional<SafetyRefusal> refusal;  // empty: the target may be sent
  std::string reason;                    // a sentence with the values and the limit
  bool ok() const { return !refusal.has_value(); }
};

// Checks `target` against `limits` given the previously commanded pose (the step and the
// speed are measured from it) and the time `period_s` since that command. Returns the
// first failed check in SafetyRefusal's order. INVALID_ARGUMENT (not a verdict) when the
// caller's own inputs are wrong: invalid limits, a non-finite `previous_commanded`, or a
// `period_s` that is not positive and finite.
SafetyVerdict check_target(const SafetyLimits& limits, const PoseTarget& target,
                           const geometry::Pose& previous_commanded, double period_s);

}  // namespace pnp::robot
