#include "sim/step_rules.h"

#include "common/error.h"
#include "common/validate.h"

namespace pnp::sim {

void require_steppable(std::span<const double> action, std::span<const double> goal,
                       bool needs_reset, int elapsed_steps) {
  require_finite_vector(action, kActionSize, "action");
  require_finite_vector(goal, kGoalSize, "goal");
  if (needs_reset) {
    throw_failed_precondition(elapsed_steps == 0
                                  ? "step: no episode has started; call reset() first"
                                  : "step: the episode ended after 50 steps; call reset()");
  }
}

Action clipped_action(std::span<const double> action) {
  return Eigen::Map<const Action>(action.data()).cwiseMax(-1.0).cwiseMin(1.0);
}

void score_step(StepResult& result, const TaskState& state, Objective objective,
                const Goal& agent_goal, const Goal& episode_goal, bool needs_reset) {
  result.achieved_goal = achieved_goal(objective, state);
  result.reward = compute_reward(result.achieved_goal, agent_goal);
  result.task_success = is_task_success(state.object, episode_goal);
  result.objective_done = objective_done_for_goal(objective, state, agent_goal);
  result.episode_over = needs_reset || result.fault != PhysicsFault::kNone;
}

}  // namespace pnp::sim
