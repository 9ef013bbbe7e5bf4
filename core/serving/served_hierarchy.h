#pragma once
// The hierarchy an inference server answers with: the promoted choreographer and the
// three promoted experts (a ServedPolicy, see served_policy.h). Each lease wraps an
// rl::HierarchyController. The controllers share one ActorBatcher per expert: concurrent
// requests that run the same subtask are answered by one batched forward pass.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "rl/choreographer_checkpoint.h"
#include "rl/expert_checkpoint.h"
#include "serving/actor_batcher.h"
#include "serving/served_policy.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "store/store.h"

namespace pnp::serving {

// Checkpoint ids serving approach, manipulate, retract and the choreographer.
struct ServedIds {
  std::array<std::int64_t, sim::kNumSubtasks> experts{};
  std::int64_t choreographer = 0;
  bool operator==(const ServedIds&) const = default;
};

class ServedHierarchy final : public ServedPolicy {
 public:
  // Loads the checkpoints `promotions` (one consistent set: Store::promotions()) name for
  // the hierarchy. FAILED_PRECONDITION naming the roles not promoted
  // yet; DATA_LOSS for a corrupted checkpoint; INVALID_ARGUMENT if the checkpoints were
  // trained on different robots. The object served is the retract expert's (a retract
  // fine-tuned for a new shape serves beside experts trained on another).
  static std::shared_ptr<const ServedHierarchy> load_promoted(
      store::Store& store, std::span<const store::Promotion> promotions);
  // The ids load_promoted would serve (without loading), or nullopt if a role is missing.
  static std::optional<ServedIds> promoted_ids(std::span<const store::Promotion> promotions);

  // Builds from already-loaded checkpoints (tests, tools).
  ServedHierarchy(rl::LoadedChoreographer choreographer,
                  std::array<rl::LoadedExpert, sim::kNumSubtasks> experts, ServedIds ids);

  const ServedIds& ids() const { return ids_; }
  PolicyKind kind() const override { return PolicyKind::kHierarchy; }
  // approach, manipulate, retract, hlc
  std::vector<std::int64_t> checkpoint_ids() const override;
  sim::Robot robot() const override { return robot_; }
  sim::ObjectShape object() const override { return object_; }
  sim::WorldProfile world() const override { return world_; }
  sim::Actuation actuation() const override { return actuation_; }
  // Per expert (approach, manipulate, retract).
  std::vector<BatchStats> batch_stats() const override;

 protected:
  std::unique_ptr<PolicyController> make_controller() const override;

 private:
  rl::LoadedChoreographer choreographer_;
  std::array<rl::LoadedExpert, sim::kNumSubtasks> experts_;
  std::array<std::shared_ptr<ActorBatcher>, sim::kNumSubtasks> batchers_;
  ServedIds ids_;
  sim::Robot robot_;
  sim::ObjectShape object_;
  sim::WorldProfile world_;
  sim::Actuation actuation_;
};

}  // namespace pnp::serving
