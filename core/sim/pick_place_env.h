#pragma once
// One goal-conditioned pick-and-place environment over a shared WorldModel.
//
// Control follows the original Fetch environment: the gripper is welded to a mocap
// target; action xyz (clipped to [-1, 1]) times 0.05 m moves that target each step (in
// the paper world from the previous target, kept inside the workspace box; in gym from
// the gripper's current position, unclamped); the gripper keeps pointing down; action[3]
// moves both fingers' position targets from their current positions by action[3] times
// their range (paper) or in metres (gym); +1 opens, -1 closes. A step is 20 physics
// substeps of 2 ms; an episode is 50 steps. world_profile.h has every difference.
//
// Inputs are validated before anything touches the physics: a refused call changes
// nothing. A physics instability (a MuJoCo bad-state warning or a non-finite state) is
// reported in the step's result and the world is reset to a fresh episode.

#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <span>

#include "common/rng.h"
#include "sim/environment.h"
#include "sim/gravity_compensation.h"
#include "sim/mujoco_data.h"
#include "sim/observation.h"
#include "sim/subtask.h"
#include "sim/world_layout.h"
#include "sim/world_model.h"

namespace pnp::sim {

class PickPlaceEnv final : public Environment {
 public:
  explicit PickPlaceEnv(std::shared_ptr<const WorldModel> world);

  // Starts an episode whose object and goal are drawn from `seed` alone.
  const Observation& reset(std::uint64_t seed) override;

  // action: 4 finite values; goal: 3 finite values (the goal the agent acts on, used for
  // the reward). Throws INVALID_ARGUMENT for bad input and FAILED_PRECONDITION before
  // reset() or after the episode's last step.
  StepResult step(std::span<const double> action, std::span<const double> goal,
                  Objective objective) override;
  using Environment::step;

  const Observation& observation() const override { return observation_; }
  const Goal& episode_goal() const override { return episode_goal_; }
  TaskState task_state() const override;
  Eigen::Vector3d objective_goal(Objective objective) const;
  int elapsed_steps() const override { return elapsed_steps_; }
  int episode_steps() const override { return layout::kEpisodeSteps; }
  bool needs_reset() const override { return needs_reset_; }
  const WorldModel& world() const { return *world_; }

  // Direct access for controllers built on this world (the robot controller stand-in)
  // and for tests. Callers that change the state own the consequences.
  const mjModel* mj_model() const { return world_->mj(); }
  mjData* mj_data() { return data_.get(); }
  const mjData* mj_data() const { return data_.get(); }

 private:
  void start_episode();
  void apply_action(const Action& action);
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
