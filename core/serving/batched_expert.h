#pragma once
// A learned subtask expert whose actor is shared by every controller of a served
// hierarchy through an ActorBatcher, so concurrent requests on the same subtask run as
// one batch. Same output as rl::LearnedExpert (the gripper scripted when not learned);
// clones share the batcher, which is thread-safe.

#include <memory>
#include <optional>

#include "serving/actor_batcher.h"
#include "sim/gripper_script.h"
#include "sim/subtask_policy.h"

namespace pnp::serving {

class BatchedExpert final : public sim::SubtaskPolicy {
 public:
  BatchedExpert(std::shared_ptr<ActorBatcher> batcher,
                std::optional<sim::GripperScript> scripted_gripper)
      : batcher_(std::move(batcher)), scripted_gripper_(scripted_gripper) {}

  sim::Action act(sim::Subtask subtask, const sim::Observation& observation, const sim::Goal& goal,
                  const sim::TaskState& state) override;
  std::unique_ptr<sim::SubtaskPolicy> clone() const override;

 private:
  std::shared_ptr<ActorBatcher> batcher_;
  std::optional<sim::GripperScript> scripted_gripper_;
};

}  // namespace pnp::serving
