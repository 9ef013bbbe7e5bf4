#include "serving/batched_expert.h"

#include "sim/gripper_script.h"

namespace pnp::serving {

sim::Action BatchedExpert::act(sim::Subtask subtask, const sim::Observation& observation,
                               const sim::Goal& goal, const sim::TaskState& state) {
  sim::Action a = batcher_->act(observation, goal);
  if (scripted_gripper_) a(3) = sim::scripted_gripper(*scripted_gripper_, subtask, state);
  return a;
}

std::unique_ptr<sim::SubtaskPolicy> BatchedExpert::clone() const {
  return std::make_unique<BatchedExpert>(*this);
}

}  // namespace pnp::serving
