#include "sim/gripper_script.h"

#include "common/enum_names.h"
#include "common/error.h"
#include "sim/scripted_expert.h"

namespace pnp::sim {

std::string_view gripper_script_name(GripperScript script) {
  switch (script) {
    case GripperScript::kGraspRule:
      return "grasp_rule";
    case GripperScript::kPerSubtask:
      return "per_subtask";
  }
  throw_internal("gripper_script_name: unknown GripperScript value");
}

GripperScript parse_gripper_script(std::string_view name, std::string_view field) {
  return parse_enum<GripperScript>(name, kAllGripperScripts, &gripper_script_name, field);
}

double scripted_gripper(GripperScript script, Subtask subtask, const TaskState& s) {
  switch (script) {
    case GripperScript::kGraspRule:
      return scripted_action(subtask, s)(3);
    case GripperScript::kPerSubtask:
      return subtask == Subtask::kApproach ? 1.0 : -1.0;
  }
  throw_internal("scripted_gripper: unknown GripperScript value");
}

}  // namespace pnp::sim
