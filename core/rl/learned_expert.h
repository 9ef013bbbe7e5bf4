#pragma once
// A learned subtask expert as a SubtaskPolicy: the deterministic actor on the subtask's
// goal. When the gripper is not learned, its command is a script's (sim/gripper_script.h).

#include <memory>
#include <optional>
#include <string_view>

#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "sim/gripper_script.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

class LearnedExpert final : public sim::SubtaskPolicy {
 public:
  // `scripted_gripper`: nullopt when the actor's own gripper command is used.
  LearnedExpert(ActorSnapshot actor, std::optional<sim::GripperScript> scripted_gripper)
      : actor_(std::move(actor)), scripted_gripper_(scripted_gripper) {}

  sim::Action act(sim::Subtask subtask, const sim::Observation& observation, const sim::Goal& goal,
                  const sim::TaskState& state) override;
  std::unique_ptr<sim::SubtaskPolicy> clone() const override;

 private:
  ActorSnapshot actor_;
  std::optional<sim::GripperScript> scripted_gripper_;
};

// The expert a checkpoint holds, refused (INVALID_ARGUMENT naming `field`) unless it is a
// `role` checkpoint.
std::unique_ptr<LearnedExpert> learned_expert_from(const LoadedExpert& checkpoint,
                                                   std::string_view role, std::string_view field);

}  // namespace pnp::rl
