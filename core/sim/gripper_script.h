#pragma once
// How an expert's gripper is commanded when its actor does not learn it.
//
//   grasp_rule   open until the grip point is within thresholds::kGraspTolerance_m of the
//                object's centre during manipulate, then closed; open in approach,
//                closed in retract: the scripted experts' own rule (domain knowledge of
//                when to grasp). Preset `ours`.
//   per_subtask  the paper's original code: a constant per subtask, whatever the state
//                (approach open; manipulate and retract closed). Preset `paper`.
//
// A learned gripper takes the actor's own command instead (DdpgHerConfig::learn_gripper).

#include <array>
#include <string_view>

#include "sim/subtask.h"

namespace pnp::sim {

enum class GripperScript { kGraspRule, kPerSubtask };

inline constexpr std::array<GripperScript, 2> kAllGripperScripts{GripperScript::kGraspRule,
                                                                 GripperScript::kPerSubtask};

std::string_view gripper_script_name(GripperScript script);
// "grasp_rule" or "per_subtask"; anything else is INVALID_ARGUMENT naming `field`.
GripperScript parse_gripper_script(std::string_view name,
                                   std::string_view field = "gripper_script");

// The gripper command (+1 opens, -1 closes) for `subtask` in state `s`.
double scripted_gripper(GripperScript script, Subtask subtask, const TaskState& s);

}  // namespace pnp::sim
