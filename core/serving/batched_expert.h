#pragma once
// A learned subtask expert whose actor is shared by every controller of a served
// hierarchy through an ActorBatcher, so concurrent requests on the same subtask run as
// one batch. Same output as rl::LearnedExpert (the gripper scripted when not learned);
// clones share the batcher, which is thread-safe.

#include <memory>

#include "serving/actor_batcher.h"
#include "sim/subtask_policy.h"

namespace pnp::serving {

class BatchedExpert final : public sim::SubtaskPolicy {
 public:
  BatchedExpert(std::shared_ptr<ActorBatcher> batcher, bool learn_gripper)
      : batcher_(std::move(batcher)), learn_gripper_(learn_gripper) {}

  sim::Action act(sim::Subtask subtask, const sim::Observation& observation, const sim::Goal& goal,
                  const sim::TaskState& state) override;
  std::unique_ptr<sim::SubtaskPolicy> clone() const override;

 private:
  std::shared_ptr<ActorBatcher> batcher_;
  bool learn_gripper_;
};

}  // namespace pnp::serving
