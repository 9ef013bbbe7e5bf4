#pragma once
// The three subtasks of pick and place, defined in one place: each one's goal, the
// achieved goal it is scored on, its termination predicate and its step cap. Training,
// evaluation, the choreographer and the robot gateway all use these functions, so one
// set of thresholds governs them all.
//
//   subtask     goal                          achieved   ends when
//   approach    object + (0, 0, 0.03)         gripper    gripper within 0.02 m of it, open
//   manipulate  object centre                 gripper    object grasped (see below)
//   retract     episode goal                  object     object within 0.01 m of it, held
//
// An Objective is what one step is scored against: one of the subtasks, or the whole
// task (end-to-end policies: achieved = object, goal = episode goal, never "done").

#include <Eigen/Core>
#include <array>
#include <string_view>

#include "sim/observation.h"

namespace pnp::sim {

enum class Subtask { kApproach = 0, kManipulate = 1, kRetract = 2 };
inline constexpr int kNumSubtasks = 3;
inline constexpr std::array<Subtask, kNumSubtasks> kAllSubtasks{
    Subtask::kApproach, Subtask::kManipulate, Subtask::kRetract};

enum class Objective { kApproach = 0, kManipulate = 1, kRetract = 2, kTask = 3 };
inline constexpr std::array<Objective, 4> kAllObjectives{
    Objective::kApproach, Objective::kManipulate, Objective::kRetract, Objective::kTask};

namespace thresholds {
inline constexpr double kPreGraspHeight_m = 0.03;     // approach target above the object
inline constexpr double kApproachTolerance_m = 0.02;  // approach done within this
// ... with the pads this far clear of the object's width: a pre-grasp pose with closed
// fingers made manipulate push the object away while opening on the way down.
inline constexpr double kPreGraspOpening_m = 0.01;
inline constexpr double kGraspTolerance_m = 0.015;   // gripper this close to the object centre
inline constexpr double kGraspGapSlack_m = 0.004;    // pads within this of the object's width
inline constexpr double kRetractTolerance_m = 0.01;  // retract done within this of the goal
// Held (retract): pads closed on the object and the gripper within this of its centre;
// looser than the grasp tolerance, since a carried object may shift in the hand.
inline constexpr double kHoldTolerance_m = 0.03;
// Step caps in gym's 50-step episode; a longer episode scales them (step_cap below).
inline constexpr int kApproachStepCap = 20;
inline constexpr int kManipulateStepCap = 15;
inline constexpr int kRetractStepCap = 50;  // the rest of the episode
}  // namespace thresholds

// What the predicates need: read from an observation plus the episode's goal and the
// object's grasp width, so that services and clients evaluate them exactly as the
// environment does.
struct TaskState {
  Eigen::Vector3d gripper;
  Eigen::Vector3d object;
  double finger_gap_m = 0;
  Eigen::Vector3d episode_goal;
  double object_width_m = 0;  // extent the fingers close on

  static TaskState from(const Observation& o, const Goal& episode_goal, double object_width_m);
};

Objective objective_of(Subtask subtask);
std::string_view subtask_name(Subtask subtask);
std::string_view objective_name(Objective objective);
Subtask parse_subtask(std::string_view name, std::string_view field = "subtask");
Objective parse_objective(std::string_view name, std::string_view field = "objective");

Eigen::Vector3d objective_goal(Objective objective, const TaskState& s);
Eigen::Vector3d achieved_goal(Objective objective, const TaskState& s);
bool objective_done(Objective objective, const TaskState& s);
// The same predicate with `goal` in place of the objective's own goal: how hindsight
// relabelling decides whether a relabelled transition is terminal. objective_done(o, s)
// is objective_done_for_goal(o, s, objective_goal(o, s)).
bool objective_done_for_goal(Objective objective, const TaskState& s, const Eigen::Vector3d& goal);
// A subtask's step cap in an episode of `episode_steps` steps: its share of gym's 50
// (above), scaled to the episode and rounded down. The arm's 75 steps give 30, 22 and
// 75: the arm moves the hand slower, and a manipulate capped at 15 steps ran out before
// the Franka Hand had closed on the cylinder (scripted: 0.84 of 300, 0.98 at 20 steps).
// INVALID_ARGUMENT unless episode_steps is positive.
int step_cap(Subtask subtask, int episode_steps);
// All three caps, indexed by Subtask: what a sequencer of the subtasks keeps.
using StepCaps = std::array<int, kNumSubtasks>;
StepCaps step_caps(int episode_steps);

// The object is grasped: gripper centred on it and the pads closed onto its sides.
bool is_grasped(const TaskState& s);
// The object is still in the hand: pads closed on it, gripper near its centre.
bool is_held(const TaskState& s);

// Dense reward: minus the Euclidean distance. Pure, so HER can relabel with it.
double compute_reward(const Eigen::Vector3d& achieved, const Eigen::Vector3d& goal);

// Task success is always judged by the object, never by the gripper.
bool is_task_success(const Eigen::Vector3d& object, const Eigen::Vector3d& episode_goal);

}  // namespace pnp::sim
