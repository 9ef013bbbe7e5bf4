#include "rl/hierarchy_controller.h"

#include <algorithm>

#include "common/error.h"
#include "common/validate.h"
#include "rl/hlc_episode.h"
#include "sim/scripted_expert.h"

namespace pnp::rl {

HierarchyController::HierarchyController(ChoreographerNet choreographer, Experts experts,
                                         double object_width_m, int episode_steps)
    : net_(std::move(choreographer)),
      experts_(std::move(experts)),
      object_width_m_(object_width_m),
      episode_steps_(episode_steps),
      caps_(sim::step_caps(episode_steps)) {
  for (const auto& e : experts_)
    if (!e) throw_internal("HierarchyController: an expert is missing");
  reset();
}

void HierarchyController::reset(int episode_steps) {
  caps_ = sim::step_caps(episode_steps);
  episode_steps_ = episode_steps;
  reset();
}

void HierarchyController::reset() {
  net_.reset_state();
  current_.reset();
  steps_in_subtask_ = 0;
  last_goal_ = sim::Goal::Zero();
  steps_ = 0;
  placed_ = false;
  value_ = 0;
  probabilities_ = {};
}

bool HierarchyController::running_subtask_ended(const sim::TaskState& state) const {
  if (!current_) return true;
  if (steps_in_subtask_ >= caps_[static_cast<std::size_t>(*current_)]) return true;
  // Against the goal the last step acted on, as the environment judges it.
  return steps_in_subtask_ >= 1 &&
         sim::objective_done_for_goal(sim::objective_of(*current_), state, last_goal_);
}

HierarchyController::Decision HierarchyController::act(const sim::Observation& observation,
                                                       const sim::Goal& episode_goal) {
  require_finite_vector({observation.data(), sim::kObservationSize}, sim::kObservationSize,
                        "observation");
  require_finite_vector({episode_goal.data(), sim::kGoalSize}, sim::kGoalSize, "goal");
  const sim::TaskState state = sim::TaskState::from(observation, episode_goal, object_width_m_);
  Decision d;
  ++steps_;
  if (!placed_ && current_ == sim::Subtask::kRetract && steps_in_subtask_ >= 1 &&
      sim::objective_done(sim::Objective::kRetract, state)) {
    placed_ = true;
  }
  if (placed_) {
    d.subtask = sim::Subtask::kRetract;
    d.action = sim::idle_action();
    d.placed = true;
    d.value = value_;
    d.probabilities = probabilities_;
    return d;
  }
  if (running_subtask_ended(state)) {
    net_.encode(observation, episode_goal, state, input_);
    std::array<double, sim::kNumSubtasks> logits{};
    net_.step(input_, cache_, logits, value_);
    probabilities_ = decision_probabilities(logits, state, net_.spec());
    const auto best = std::max_element(probabilities_.begin(), probabilities_.end());
    current_ = sim::kAllSubtasks[static_cast<std::size_t>(best - probabilities_.begin())];
    steps_in_subtask_ = 0;
    d.decided = true;
  }
  const sim::Subtask subtask = *current_;
  const sim::Goal goal = sim::objective_goal(sim::objective_of(subtask), state);
  last_goal_ = goal;
  d.subtask = subtask;
  d.action = experts_[static_cast<std::size_t>(subtask)]->act(subtask, observation, goal, state);
  d.value = value_;
  d.probabilities = probabilities_;
  ++steps_in_subtask_;
  return d;
}

}  // namespace pnp::rl
