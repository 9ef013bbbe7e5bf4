#include "rl/learned_expert.h"

#include "common/error.h"
#include "sim/gripper_script.h"

namespace pnp::rl {

sim::Action LearnedExpert::act(sim::Subtask subtask, const sim::Observation& observation,
                               const sim::Goal& goal, const sim::TaskState& state) {
  sim::Action a = actor_.act(observation, goal);
  if (scripted_gripper_) a(3) = sim::scripted_gripper(*scripted_gripper_, subtask, state);
  return a;
}

std::unique_ptr<sim::SubtaskPolicy> LearnedExpert::clone() const {
  return std::make_unique<LearnedExpert>(*this);
}

std::unique_ptr<LearnedExpert> learned_expert_from(const LoadedExpert& checkpoint,
                                                   std::string_view role, std::string_view field) {
  if (checkpoint.meta.role != role) {
    throw_invalid_argument(std::string(field), "a checkpoint of role " + std::string(role),
                           "role " + checkpoint.meta.role);
  }
  return std::make_unique<LearnedExpert>(
      ActorSnapshot(checkpoint.actor, checkpoint.observation_normalizer, checkpoint.goal_normalizer,
                    checkpoint.meta.clip_obs),
      scripted_gripper_of(checkpoint.meta));
}

}  // namespace pnp::rl
