#include "rl/learned_expert.h"

#include "sim/scripted_expert.h"

namespace pnp::rl {

sim::Action LearnedExpert::act(sim::Subtask subtask, const sim::Observation& observation,
                               const sim::Goal& goal, const sim::TaskState& state) {
  sim::Action a = actor_.act(observation, goal);
  if (!learn_gripper_) a(3) = sim::scripted_action(subtask, state)(3);
  return a;
}

std::unique_ptr<sim::SubtaskPolicy> LearnedExpert::clone() const {
  return std::make_unique<LearnedExpert>(*this);
}

}  // namespace pnp::rl
