#include "sim/subtask_policy.h"

#include "sim/scripted_expert.h"

namespace pnp::sim {

Action ScriptedPolicy::act(Subtask subtask, const Observation& /*observation*/,
                           const Goal& /*goal*/, const TaskState& state) {
  return scripted_action(subtask, state);
}

std::unique_ptr<SubtaskPolicy> ScriptedPolicy::clone() const {
  return std::make_unique<ScriptedPolicy>();
}

}  // namespace pnp::sim
