#pragma once
// What a rollout needs of a pick-and-place environment, wherever its physics runs: in
// this process (PickPlaceEnv) or in a simulation service on another machine
// (clients/sim_client). Rollouts, trainers and evaluations are written against this,
// so where the physics runs is a deployment choice, not a code path.

#include <cstdint>
#include <span>
#include <string_view>

#include "sim/observation.h"
#include "sim/subtask.h"

namespace pnp::sim {

enum class PhysicsFault {
  kNone,
  kUnstable,   // MuJoCo flagged a bad qpos/qvel/qacc (it may have reset its data)
  kNonFinite,  // NaN or Inf in the state
  kCapacity,   // contact or constraint buffer full: contacts were dropped
  kEjected,    // the object moves impossibly fast or leaves the scene: a contact blew up
};

constexpr std::string_view physics_fault_name(PhysicsFault fault) {
  switch (fault) {
    case PhysicsFault::kNone:
      return "none";
    case PhysicsFault::kUnstable:
      return "unstable";
    case PhysicsFault::kNonFinite:
      return "non-finite";
    case PhysicsFault::kCapacity:
      return "capacity";
    case PhysicsFault::kEjected:
      return "ejected";
  }
  return "unknown";
}

struct StepResult {
  Observation observation;        // after the step (a fresh episode's after a fault)
  Eigen::Vector3d achieved_goal;  // for the objective the step was scored on
  double reward = 0;              // -||achieved - goal|| with the goal passed to step()
  bool task_success = false;      // object within 0.05 m of the episode goal
  // The objective's termination predicate on the state after the step, judged against
  // the goal passed to step() (the goal acted on), as the replay judges a stored
  // transition: one rule, so a stored done equals the environment's.
  bool objective_done = false;
  bool episode_over = false;  // the 50th step was taken (reset() before stepping again),
                              // or a fault ended it (a fresh episode has already begun)
  PhysicsFault fault = PhysicsFault::kNone;
};

class Environment {
 public:
  virtual ~Environment() = default;

  // Starts an episode whose object and goal are drawn from `seed` alone: the same seed
  // gives the same episode in any process.
  virtual const Observation& reset(std::uint64_t seed) = 0;

  // action: 4 finite values; goal: 3 finite values (the goal the agent acts on, used for
  // the reward). INVALID_ARGUMENT for bad input, FAILED_PRECONDITION before reset() or
  // after the episode's last step; a remote environment adds UNAVAILABLE.
  virtual StepResult step(std::span<const double> action, std::span<const double> goal,
                          Objective objective) = 0;
  StepResult step(const Action& action, const Goal& goal, Objective objective) {
    return step(std::span<const double>(action.data(), kActionSize),
                std::span<const double>(goal.data(), kGoalSize), objective);
  }

  virtual const Observation& observation() const = 0;
  virtual const Goal& episode_goal() const = 0;
  virtual TaskState task_state() const = 0;
  virtual int elapsed_steps() const = 0;
  virtual bool needs_reset() const = 0;
  // The steps of an episode: sim::episode_steps of the environment's actuation (gym's 50
  // with the mocap hand, the arm's 75). Subtask step caps scale with it (sim::step_cap).
  virtual int episode_steps() const = 0;

 protected:
  Environment() = default;
  Environment(const Environment&) = default;
  Environment(Environment&&) = default;
  Environment& operator=(const Environment&) = default;
  Environment& operator=(Environment&&) = default;
};

}  // namespace pnp::sim
