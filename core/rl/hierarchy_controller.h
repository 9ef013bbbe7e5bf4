#pragma once
// The trained hierarchy driven one environment step at a time, for a live episode (the
// inference service, the robot gateway): the choreographer decides greedily when no
// subtask is running or the running one has ended (its predicate fired after at least
// one step, or its step cap), and that subtask's expert produces the action. Once retract
// has placed the object the arm holds still. Same rule as run_hlc_episode's greedy
// evaluation, step for step (tested).

#include <array>
#include <memory>
#include <optional>

#include "rl/choreographer_net.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

class HierarchyController {
 public:
  using Experts = std::array<std::unique_ptr<sim::SubtaskPolicy>, sim::kNumSubtasks>;

  // object_width_m: the extent the fingers close on (the grasp predicate needs it);
  // episode_steps: the episode the hierarchy plays (Environment::episode_steps, or the
  // served policy's actuation's), which sets the subtask step caps (sim::step_cap).
  HierarchyController(ChoreographerNet choreographer, Experts experts, double object_width_m,
                      int episode_steps);

  struct Decision {
    sim::Subtask subtask = sim::Subtask::kApproach;
    sim::Action action = sim::Action::Zero();
    double value = 0;  // the choreographer's, at its latest decision
    std::array<double, sim::kNumSubtasks> probabilities{};
    bool decided = false;  // the choreographer chose anew at this step
    bool placed = false;   // retract has placed the object: hold still
  };

  void reset();  // a new episode as long as the last
  // A new episode of `episode_steps` steps: the subtask caps scale to it (a mocap-trained
  // hierarchy played on the arm's 75-step episode gets the arm's caps).
  void reset(int episode_steps);
  // The action for the state after the previous action. Throws INVALID_ARGUMENT for a
  // non-finite observation or goal (naming it).
  Decision act(const sim::Observation& observation, const sim::Goal& episode_goal);
  int steps() const { return steps_; }
  int episode_steps() const { return episode_steps_; }

 private:
  bool running_subtask_ended(const sim::TaskState& state) const;

  ChoreographerNet net_;
  Experts experts_;
  double object_width_m_;
  int episode_steps_;
  sim::StepCaps caps_;
  nn::Matrix input_;
  DecisionCache cache_;
  std::optional<sim::Subtask> current_;
  int steps_in_subtask_ = 0;
  sim::Goal last_goal_ = sim::Goal::Zero();  // the goal the last action was for
  int steps_ = 0;
  bool placed_ = false;
  double value_ = 0;
  std::array<double, sim::kNumSubtasks> probabilities_{};
};

}  // namespace pnp::rl
