#pragma once
// The fixed order approach -> manipulate -> retract: which subtask runs now, and when to
// move on (its termination predicate fired, or its step cap was reached). After retract
// the sequence is idle (hold still, gripper closed, until the episode ends). Shared by
// the scripted pipeline, the environment benchmark and the tests, so the rule is written
// once.

#include "sim/subtask.h"

namespace pnp::sim {

class SubtaskSequence {
 public:
  // Caps as step_caps gives them for an episode of `episode_steps` (Environment::episode_steps).
  explicit SubtaskSequence(int episode_steps) : caps_(step_caps(episode_steps)) {}

  bool idle() const { return stage_ >= kNumSubtasks; }
  Subtask current() const { return kAllSubtasks[static_cast<std::size_t>(stage_)]; }  // not idle
  // What the step is scored against: the current subtask, or the whole task when idle.
  Objective objective() const { return idle() ? Objective::kTask : objective_of(current()); }
  int steps_in_stage() const { return steps_in_stage_; }

  // Records one step of the current subtask; returns true if that subtask has just ended.
  bool record_step(bool objective_done) {
    if (idle()) return false;
    ++steps_in_stage_;
    if (!objective_done && steps_in_stage_ < caps_[static_cast<std::size_t>(stage_)]) return false;
    ++stage_;
    steps_in_stage_ = 0;
    return true;
  }

 private:
  StepCaps caps_;
  int stage_ = 0;
  int steps_in_stage_ = 0;
};

}  // namespace pnp::sim
