#pragma once
// What every environment does around its physics, whatever moves the hand: the checks a
// step's input passes before anything is touched, and how a step is scored. One copy, so
// the mocap world, the arm-actuated world and a remote environment refuse and score alike.

#include <span>

#include "sim/environment.h"

namespace pnp::sim {

// INVALID_ARGUMENT for an action that is not 4 finite values or a goal that is not 3;
// FAILED_PRECONDITION before the first reset() or after the episode's last step.
void require_steppable(std::span<const double> action, std::span<const double> goal,
                       bool needs_reset, int elapsed_steps);

// The action each environment applies: clipped to [-1, 1].
Action clipped_action(std::span<const double> action);

// Fills the scoring fields of `result` (achieved goal, reward, task success, objective
// done, episode over) from the state after the step, the goal the agent acted on and the
// episode's goal. `result.fault` must already be set.
void score_step(StepResult& result, const TaskState& state, Objective objective,
                const Goal& agent_goal, const Goal& episode_goal, bool needs_reset);

}  // namespace pnp::sim
