#pragma once
// What runs a subtask: the scripted expert or a learned one. The pipeline and the
// choreographer only see this interface. Implementations keep per-call scratch space,
// so a policy is not shared between threads: each worker uses its own clone().

#include <memory>

#include "sim/observation.h"
#include "sim/subtask.h"

namespace pnp::sim {

class SubtaskPolicy {
 public:
  virtual ~SubtaskPolicy() = default;
  // `goal` is the subtask's goal (objective_goal); `state` is the same moment decoded.
  virtual Action act(Subtask subtask, const Observation& observation, const Goal& goal,
                     const TaskState& state) = 0;
  virtual std::unique_ptr<SubtaskPolicy> clone() const = 0;
};

class ScriptedPolicy final : public SubtaskPolicy {
 public:
  Action act(Subtask subtask, const Observation& observation, const Goal& goal,
             const TaskState& state) override;
  std::unique_ptr<SubtaskPolicy> clone() const override;
};

}  // namespace pnp::sim
