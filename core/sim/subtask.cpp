#include "sim/subtask.h"

#include <algorithm>
#include <string>

#include "common/enum_names.h"
#include "common/error.h"
#include "sim/world_layout.h"

namespace pnp::sim {

TaskState TaskState::from(const Observation& o, const Goal& episode_goal, double object_width_m) {
  return {gripper_position(o), object_position(o), finger_gap(o), episode_goal, object_width_m};
}

Objective objective_of(Subtask subtask) {
  return static_cast<Objective>(subtask);
}

std::string_view subtask_name(Subtask subtask) {
  return objective_name(objective_of(subtask));
}

std::string_view objective_name(Objective objective) {
  switch (objective) {
    case Objective::kApproach:
      return "approach";
    case Objective::kManipulate:
      return "manipulate";
    case Objective::kRetract:
      return "retract";
    case Objective::kTask:
      return "task";
  }
  throw_internal("objective_name: unknown Objective value");
}

Subtask parse_subtask(std::string_view name, std::string_view field) {
  return parse_enum<Subtask>(name, kAllSubtasks, &subtask_name, field);
}

Objective parse_objective(std::string_view name, std::string_view field) {
  return parse_enum<Objective>(name, kAllObjectives, &objective_name, field);
}

Eigen::Vector3d objective_goal(Objective objective, const TaskState& s) {
  switch (objective) {
    case Objective::kApproach:
      return s.object + Eigen::Vector3d(0, 0, thresholds::kPreGraspHeight_m);
    case Objective::kManipulate:
      return s.object;
    case Objective::kRetract:
    case Objective::kTask:
      return s.episode_goal;
  }
  throw_internal("objective_goal: unknown Objective value");
}

Eigen::Vector3d achieved_goal(Objective objective, const TaskState& s) {
  switch (objective) {
    case Objective::kApproach:
    case Objective::kManipulate:
      return s.gripper;
    case Objective::kRetract:
    case Objective::kTask:
      return s.object;
  }
  throw_internal("achieved_goal: unknown Objective value");
}

bool is_grasped(const TaskState& s) {
  return objective_done_for_goal(Objective::kManipulate, s, s.object);
}

bool is_held(const TaskState& s) {
  return (s.gripper - s.object).norm() < thresholds::kHoldTolerance_m &&
         s.finger_gap_m < s.object_width_m + thresholds::kGraspGapSlack_m;
}

bool objective_done_for_goal(Objective objective, const TaskState& s, const Eigen::Vector3d& goal) {
  switch (objective) {
    case Objective::kApproach:
      return (s.gripper - goal).norm() < thresholds::kApproachTolerance_m &&
             s.finger_gap_m > s.object_width_m + thresholds::kPreGraspOpening_m;
    case Objective::kManipulate:  // the grasp predicate, centred on `goal`
      return (s.gripper - goal).norm() < thresholds::kGraspTolerance_m &&
             s.finger_gap_m < s.object_width_m + thresholds::kGraspGapSlack_m;
    case Objective::kRetract:  // held there: a dropped object that rests at `goal` is not
                               // done, or relabelled goals would teach letting go early
      return (s.object - goal).norm() < thresholds::kRetractTolerance_m && is_held(s);
    case Objective::kTask:
      return false;  // the whole task runs to the episode's end
  }
  throw_internal("objective_done_for_goal: unknown Objective value");
}

bool objective_done(Objective objective, const TaskState& s) {
  return objective_done_for_goal(objective, s, objective_goal(objective, s));
}

int step_cap(Subtask subtask, int episode_steps) {
  if (episode_steps <= 0) {
    throw_invalid_argument("episode_steps", "a positive number of steps",
                           std::to_string(episode_steps));
  }
  const int gym_cap = [subtask] {
    switch (subtask) {
      case Subtask::kApproach:
        return thresholds::kApproachStepCap;
      case Subtask::kManipulate:
        return thresholds::kManipulateStepCap;
      case Subtask::kRetract:
        return thresholds::kRetractStepCap;
    }
    throw_internal("step_cap: unknown Subtask value");
  }();
  return std::max(1, gym_cap * episode_steps / layout::kEpisodeSteps);
}

StepCaps step_caps(int episode_steps) {
  StepCaps caps{};
  for (Subtask subtask : kAllSubtasks) {
    caps[static_cast<std::size_t>(subtask)] = step_cap(subtask, episode_steps);
  }
  return caps;
}

double compute_reward(const Eigen::Vector3d& achieved, const Eigen::Vector3d& goal) {
  return -(achieved - goal).norm();
}

bool is_task_success(const Eigen::Vector3d& object, const Eigen::Vector3d& episode_goal) {
  return (object - episode_goal).norm() < layout::kTaskSuccessDistance;
}

}  // namespace pnp::sim
