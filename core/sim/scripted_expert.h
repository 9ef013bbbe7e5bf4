#pragma once
// Hand-engineered subtask experts: proportional controllers (gain 6) on the gripper
// position towards each subtask's goal, with the gripper open for approach, closing
// once centred for manipulate, and closed for retract. They are the prefix and suffix
// of subtask training, the behaviour-cloning teacher, and the evaluation fallback.

#include "sim/observation.h"
#include "sim/subtask.h"

namespace pnp::sim {

inline constexpr double kScriptedGain = 6.0;

Action scripted_action(Subtask subtask, const TaskState& s);

// After retract: hold still with the gripper closed until the episode ends.
Action idle_action();

}  // namespace pnp::sim
