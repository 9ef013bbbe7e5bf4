#include "sim/scripted_expert.h"

#include "common/error.h"

namespace pnp::sim {
namespace {

constexpr double kOpen = 1.0;
constexpr double kClose = -1.0;

Action toward(const Eigen::Vector3d& error, double gripper) {
  Action a;
  a.head<3>() = (kScriptedGain * error).cwiseMax(-1.0).cwiseMin(1.0);
  a(3) = gripper;
  return a;
}

}  // namespace

Action scripted_action(Subtask subtask, const TaskState& s) {
  const Objective objective = objective_of(subtask);
  const Eigen::Vector3d goal = objective_goal(objective, s);
  switch (subtask) {
    case Subtask::kApproach:
      return toward(goal - s.gripper, kOpen);
    case Subtask::kManipulate: {
      const bool centred = (s.gripper - s.object).norm() < thresholds::kGraspTolerance_m;
      return toward(goal - s.gripper, centred ? kClose : kOpen);
    }
    // Retract moves the gripper by the object's error: the object is what must arrive.
    case Subtask::kRetract:
      return toward(goal - s.object, kClose);
  }
  throw_internal("scripted_action: unknown Subtask value");
}

Action idle_action() {
  return {0.0, 0.0, 0.0, kClose};
}

}  // namespace pnp::sim
