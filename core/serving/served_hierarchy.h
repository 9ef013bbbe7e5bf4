#pragma once
// The hierarchy an inference server answers with: the promoted choreographer and the
// three promoted experts, loaded (and verified) from the store, immutable once built.
// Each request or episode borrows a HierarchyController from a pool, so concurrent
// requests never share recurrent state or scratch space, and nothing is allocated per
// request once the pool has warmed up. A server swaps in a new ServedHierarchy when a
// checkpoint is promoted; leases taken on the old one keep it alive until returned.
// The controllers share one ActorBatcher per expert: concurrent requests that run the
// same subtask are answered by one batched forward pass.

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "rl/choreographer_checkpoint.h"
#include "rl/expert_checkpoint.h"
#include "rl/hierarchy_controller.h"
#include "serving/actor_batcher.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "store/run_store.h"

namespace pnp::serving {

// Checkpoint ids serving approach, manipulate, retract and the choreographer.
struct ServedIds {
  std::array<std::int64_t, sim::kNumSubtasks> experts{};
  std::int64_t choreographer = 0;
  bool operator==(const ServedIds&) const = default;
};

class ServedHierarchy : public std::enable_shared_from_this<ServedHierarchy> {
 public:
  // Loads the promoted checkpoints. FAILED_PRECONDITION naming the roles not promoted
  // yet; DATA_LOSS for a corrupted checkpoint; INVALID_ARGUMENT if the checkpoints were
  // trained on different robots. The object served is the retract expert's (a retract
  // fine-tuned for a new shape serves beside experts trained on another).
  static std::shared_ptr<const ServedHierarchy> load_promoted(store::RunStore& store);
  // The ids load_promoted would serve (without loading), or nullopt if a role is missing.
  static std::optional<ServedIds> promoted_ids(store::RunStore& store);

  // Builds from already-loaded checkpoints (tests, tools).
  ServedHierarchy(rl::LoadedChoreographer choreographer,
                  std::array<rl::LoadedExpert, sim::kNumSubtasks> experts, ServedIds ids);

  class Lease {
   public:
    Lease(std::shared_ptr<const ServedHierarchy> owner,
          std::unique_ptr<rl::HierarchyController> controller);
    Lease(Lease&&) noexcept = default;
    Lease& operator=(Lease&&) noexcept = default;
    ~Lease();
    rl::HierarchyController& operator*() const { return *controller_; }
    rl::HierarchyController* operator->() const { return controller_.get(); }

   private:
    std::shared_ptr<const ServedHierarchy> owner_;
    std::unique_ptr<rl::HierarchyController> controller_;
  };

  // A controller reset to the start of an episode. Thread-safe.
  Lease acquire() const;

  const ServedIds& ids() const { return ids_; }
  sim::Robot robot() const { return robot_; }
  sim::ObjectShape object() const { return object_; }
  // Per expert (approach, manipulate, retract): requests and batches served so far.
  std::array<BatchStats, sim::kNumSubtasks> batch_stats() const;

 private:
  std::unique_ptr<rl::HierarchyController> make_controller() const;
  void give_back(std::unique_ptr<rl::HierarchyController> controller) const;

  rl::LoadedChoreographer choreographer_;
  std::array<rl::LoadedExpert, sim::kNumSubtasks> experts_;
  std::array<std::shared_ptr<ActorBatcher>, sim::kNumSubtasks> batchers_;
  ServedIds ids_;
  sim::Robot robot_;
  sim::ObjectShape object_;
  mutable std::mutex pool_mutex_;
  mutable std::vector<std::unique_ptr<rl::HierarchyController>> pool_;
};

}  // namespace pnp::serving
