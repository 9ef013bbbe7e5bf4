#pragma once
// The end-to-end DDPG+HER baseline an inference server answers with (a ServedPolicy, see
// served_policy.h): the promoted "e2e" checkpoint, one actor for the whole task. It acts
// exactly as rl::evaluate_end_to_end has it act: on the episode goal at every step, its
// gripper learned or scripted (for retract) as the checkpoint says, with no choreographer
// and no holding still. The controllers share one ActorBatcher, so concurrent requests
// are answered by one batched forward pass.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "rl/expert_checkpoint.h"
#include "serving/actor_batcher.h"
#include "serving/served_policy.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "store/store.h"

namespace pnp::serving {

class ServedEndToEnd final : public ServedPolicy {
 public:
  // Loads the promoted e2e checkpoint. FAILED_PRECONDITION naming e2e if none is
  // promoted; DATA_LOSS for a corrupted checkpoint; INVALID_ARGUMENT if it is not an
  // end-to-end DDPG+HER checkpoint.
  static std::shared_ptr<const ServedEndToEnd> load_promoted(
      store::Store& store, std::span<const store::Promotion> promotions);
  // The id load_promoted would serve (without loading), or nullopt if none is promoted.
  static std::optional<std::int64_t> promoted_id(std::span<const store::Promotion> promotions);

  // Builds from an already-loaded checkpoint (tests, tools). INVALID_ARGUMENT naming the
  // checkpoint unless its role is e2e and its algorithm ddpg_her.
  ServedEndToEnd(rl::LoadedExpert policy, std::int64_t checkpoint_id);

  std::int64_t checkpoint_id() const { return checkpoint_id_; }
  PolicyKind kind() const override { return PolicyKind::kEndToEnd; }
  std::vector<std::int64_t> checkpoint_ids() const override { return {checkpoint_id_}; }
  sim::Robot robot() const override { return robot_; }
  sim::ObjectShape object() const override { return object_; }
  sim::WorldProfile world() const override { return world_; }
  sim::Actuation actuation() const override { return actuation_; }
  // One entry: the e2e actor.
  std::vector<BatchStats> batch_stats() const override { return {batcher_->stats()}; }

 protected:
  std::unique_ptr<PolicyController> make_controller() const override;

 private:
  rl::LoadedExpert policy_;
  std::int64_t checkpoint_id_;
  sim::Robot robot_;
  sim::ObjectShape object_;
  sim::WorldProfile world_;
  sim::Actuation actuation_;
  std::shared_ptr<ActorBatcher> batcher_;
};

}  // namespace pnp::serving
