#include "serving/batched_expert.h"

#include "sim/scripted_expert.h"

namespace pnp::serving {

sim::Action BatchedExpert::act(sim::Subtask subtask, const sim::Observation& observation,
                               const sim::Goal& goal, const sim::TaskState& state) {
  sim::Action a = batcher_->act(observation, goal);
  if (!learn_gripper_) a(3) = sim::scripted_action(subtask, state)(3);
  return a;
}

std::unique_ptr<sim::SubtaskPolicy> BatchedExpert::clone() const {
  return std::make_unique<BatchedExpert>(*this);
}

}  // namespace pnp::serving
