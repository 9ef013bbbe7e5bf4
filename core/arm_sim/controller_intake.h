#pragma once
// What the arm's controller does with a target once its network side has taken it (the
// lease, the stream's sequence, the frame and the stamp checked): its own limits
// (controller_limits.h) first, then the arm's own refusals (reach, joint limits, a stop).
// pnp-robot-sim's controller and the arm-actuated training world both take targets
// through this one function, so a policy meets in training exactly the refusals it meets
// on the controller.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "arm_sim/controller_limits.h"
#include "arm_sim/simulated_arm.h"

namespace pnp::arm_sim {

// The outcome of a request, or the controller's condition, as the protocol reports it.
enum class ControllerStatus {
  kOk,
  kInvalidTarget,
  kUnreachable,
  kJointLimit,
  kStopped,
  kLeaseLost,
  kOutsideLimits,  // the controller's own workspace, table plane or step limit
  kStale,          // the target's stamp is too old (or missing)
};

struct ArmTarget {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // base frame
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  double gripper_width_m = 0;
  double max_speed_m_per_s = 0;  // 0: the arm's default
};

struct IntakeOutcome {
  ControllerStatus status = ControllerStatus::kOk;
  std::string error;  // why, when not kOk
  bool accepted() const { return status == ControllerStatus::kOk; }
};

// Refusals change nothing on the arm; an accepted target starts the arm's next segment.
IntakeOutcome take_into_arm(SimulatedArm& arm, const ControllerLimits& limits,
                            const ArmTarget& target);

}  // namespace pnp::arm_sim
