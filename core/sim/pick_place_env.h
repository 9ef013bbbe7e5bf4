#pragma once
// One goal-conditioned pick-and-place environment over a shared WorldModel.
//
// Control follows the original Fetch environment: the gripper is welded to a mocap
// target; action xyz (clipped to [-1, 1]) times 0.05 m moves that target each step, kept
// inside the workspace box; the gripper keeps pointing down; action[3] moves both
// fingers' position targets by action[3] times their range (+1 opens, -1 closes). A step
// is 20 physics substeps of 2 ms; an episode is 50 steps.
//
// Inputs are validated before anything touches the physics: a refused call changes
// nothing. A physics instability (a MuJoCo bad-state warning or a non-finite state) is
// reported in the step's result and the world is reset to a fresh episode.

#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <span>

#include "common/rng.h"
#include "sim/gravity_compensation.h"
#include "sim/mujoco_data.h"
#include "sim/observation.h"
#include "sim/subtask.h"
#include "sim/world_model.h"

namespace pnp::sim {

enum class PhysicsFault {
  kNone,
  kUnstable,   // MuJoCo flagged a bad qpos/qvel/qacc (it may have reset its data)
  kNonFinite,  // NaN or Inf in the state
  kCapacity,   // contact or constraint buffer full: contacts were dropped
  kEjected,    // the object moves impossibly fast or leaves the scene: a contact blew up
};

struct StepResult {
  Observation observation;        // after the step (a fresh episode's after a fault)
  Eigen::Vector3d achieved_goal;  // for the objective the step was scored on
  double reward = 0;              // -||achieved - goal|| with the goal passed to step()
  bool task_success = false;      // object within 0.05 m of the episode goal
  bool objective_done = false;    // the objective's termination predicate
  bool episode_over = false;      // the 50th step was taken (reset() before stepping again),
                                  // or a fault ended it (a fresh episode has already begun)
  PhysicsFault fault = PhysicsFault::kNone;
};

class PickPlaceEnv {
 public:
  explicit PickPlaceEnv(std::shared_ptr<const WorldModel> world);

  // Starts an episode whose object and goal are drawn from `seed` alone.
  const Observation& reset(std::uint64_t seed);

  // action: 4 finite values; goal: 3 finite values (the goal the agent acts on, used for
  // the reward). Throws INVALID_ARGUMENT for bad input and FAILED_PRECONDITION before
  // reset() or after the episode's last step.
  StepResult step(std::span<const double> action, std::span<const double> goal,
                  Objective objective);
  StepResult step(const Action& action, const Goal& goal, Objective objective) {
    return step(std::span<const double>(action.data(), kActionSize),
                std::span<const double>(goal.data(), kGoalSize), objective);
  }

  const Observation& observation() const { return observation_; }
  const Goal& episode_goal() const { return episode_goal_; }
  TaskState task_state() const;
  Eigen::Vector3d objective_goal(Objective objective) const;
  int elapsed_steps() const { return elapsed_steps_; }
  bool needs_reset() const { return needs_reset_; }
  const WorldModel& world() const { return *world_; }

  // Direct access for controllers built on this world (the robot controller stand-in)
  // and for tests. Callers that change the state own the consequences.
  const mjModel* mj_model() const { return world_->mj(); }
  mjData* mj_data() { return data_.get(); }
  const mjData* mj_data() const { return data_.get(); }

 private:
  void start_episode();
  void apply_action(const Action& action);
  PhysicsFault detect_fault() const;
  void update_observation();

  std::shared_ptr<const WorldModel> world_;
  DataPtr data_;
  GravityCompensation gravity_compensation_;
  Rng rng_;
  Observation observation_ = Observation::Zero();
  Goal episode_goal_ = Goal::Zero();
  int elapsed_steps_ = 0;
  bool needs_reset_ = true;
};

}  // namespace pnp::sim
