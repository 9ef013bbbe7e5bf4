#pragma once
// A learned subtask expert as a SubtaskPolicy: the deterministic actor on the subtask's
// goal. When the gripper is not learned, its command is the scripted expert's.

#include <memory>
#include <string_view>

#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

class LearnedExpert final : public sim::SubtaskPolicy {
 public:
  LearnedExpert(ActorSnapshot actor, bool learn_gripper)
      : actor_(std::move(actor)), learn_gripper_(learn_gripper) {}

  sim::Action act(sim::Subtask subtask, const sim::Observation& observation, const sim::Goal& goal,
                  const sim::TaskState& state) override;
  std::unique_ptr<sim::SubtaskPolicy> clone() const override;

 private:
  ActorSnapshot actor_;
  bool learn_gripper_;
};

// The expert a checkpoint holds, refused (INVALID_ARGUMENT naming `field`) unless it is a
// `role` checkpoint.
std::unique_ptr<LearnedExpert> learned_expert_from(const LoadedExpert& checkpoint,
                                                   std::string_view role, std::string_view field);

}  // namespace pnp::rl
