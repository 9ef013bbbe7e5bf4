#pragma once
// What an inference server answers with, whichever policy it serves: the promoted
// hierarchy (ServedHierarchy: choreographer + three experts) or the promoted end-to-end
// baseline (ServedEndToEnd: one DDPG+HER actor for the whole task). Loaded (and
// verified) from the store, immutable once built. Each request or episode borrows a
// PolicyController from the served policy's pool, so concurrent requests never share
// recurrent state or scratch space, and nothing is allocated per request once the pool
// has warmed up. A server swaps in a new ServedPolicy when a checkpoint it serves is
// promoted; leases taken on the old one keep it alive until returned.

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "serving/actor_batcher.h"
#include "sim/actuation.h"
#include "sim/object_shape.h"
#include "sim/observation.h"
#include "sim/robot.h"
#include "sim/subtask.h"
#include "sim/world_profile.h"
#include "store/store.h"

namespace pnp::serving {

// Which policy a server serves.
enum class PolicyKind { kHierarchy, kEndToEnd };

std::string_view policy_kind_name(PolicyKind kind);  // "hierarchy", "e2e"
// INVALID_ARGUMENT naming `field` for anything but "hierarchy" or "e2e".
PolicyKind parse_policy_kind(std::string_view name, std::string_view field = "policy");
// The store roles a kind serves, in checkpoint_ids() order: approach, manipulate,
// retract, hlc; or e2e.
std::vector<std::string> served_roles(PolicyKind kind);
// Its batched actors, in batch_stats() order: approach, manipulate, retract; or e2e.
std::vector<std::string> batched_actors(PolicyKind kind);

// One answer of a controller.
struct Decision {
  // The subtask whose expert produced the action; nullopt when one policy does the
  // whole task (end-to-end), reported as SUBTASK_UNSPECIFIED.
  std::optional<sim::Subtask> subtask;
  sim::Action action = sim::Action::Zero();
  double value = 0;  // the choreographer's, at its latest decision (0 without one)
  // Approach, manipulate, retract at the latest decision; nullopt without a choreographer.
  std::optional<std::array<double, sim::kNumSubtasks>> probabilities;
  bool decided = false;                          // the choreographer chose anew at this step
  bool placed = false;                           // the object has been placed: hold still
  std::int64_t choreographer_checkpoint_id = 0;  // 0: none
  std::int64_t expert_checkpoint_id = 0;         // the checkpoint whose actor acted
};

// One request's or episode's policy state.
class PolicyController {
 public:
  virtual ~PolicyController() = default;
  // A new episode of `episode_steps` steps (positive): the hierarchy's subtask caps scale
  // to it (sim::step_caps); the end-to-end policy has none.
  virtual void reset(int episode_steps) = 0;
  // The action for the state after the previous action, given the episode goal. Throws
  // INVALID_ARGUMENT for a non-finite observation or goal (naming it).
  virtual Decision act(const sim::Observation& observation, const sim::Goal& episode_goal) = 0;
  virtual int steps() const = 0;          // answered since reset, this one included
  virtual int episode_steps() const = 0;  // as the last reset declared
};

class ServedPolicy : public std::enable_shared_from_this<ServedPolicy> {
 public:
  virtual ~ServedPolicy() = default;
  ServedPolicy(const ServedPolicy&) = delete;
  ServedPolicy& operator=(const ServedPolicy&) = delete;

  class Lease {
   public:
    Lease(std::shared_ptr<const ServedPolicy> owner, std::unique_ptr<PolicyController> controller);
    Lease(Lease&&) noexcept = default;
    Lease& operator=(Lease&&) noexcept = default;
    ~Lease();
    PolicyController& operator*() const { return *controller_; }
    PolicyController* operator->() const { return controller_.get(); }

   private:
    std::shared_ptr<const ServedPolicy> owner_;
    std::unique_ptr<PolicyController> controller_;
  };

  // A controller reset to the start of an episode of `episode_steps` steps; 0: the episode
  // of the policy's actuation (sim::episode_steps: 50 on the mocap hand, 75 on the arm).
  // INVALID_ARGUMENT naming episode_steps outside 0..layout::kMaxEpisodeSteps. Thread-safe.
  Lease acquire(int episode_steps = 0) const;

  virtual PolicyKind kind() const = 0;
  // The checkpoints served, one per served_roles(kind()) entry, in that order.
  virtual std::vector<std::int64_t> checkpoint_ids() const = 0;
  virtual sim::Robot robot() const = 0;
  virtual sim::ObjectShape object() const = 0;
  virtual sim::WorldProfile world() const = 0;
  // How the served policy's hand followed its actions in training: kArm only when every
  // served checkpoint was trained through the arm controller.
  virtual sim::Actuation actuation() const = 0;
  // Per batched actor (batched_actors(kind()) order): requests and batches served so far.
  virtual std::vector<BatchStats> batch_stats() const = 0;

 protected:
  ServedPolicy() = default;
  virtual std::unique_ptr<PolicyController> make_controller() const = 0;
  // Builds one controller into the pool: derived constructors call it last, so that
  // anything wrong fails there rather than in the first request.
  void warm_up() const { give_back(make_controller()); }

 private:
  void give_back(std::unique_ptr<PolicyController> controller) const;

  mutable std::mutex pool_mutex_;
  mutable std::vector<std::unique_ptr<PolicyController>> pool_;
};

// The ids load_promoted would serve (without loading), in served_roles(kind) order, or
// nullopt if a role is not promoted yet.
std::optional<std::vector<std::int64_t>> promoted_checkpoint_ids(
    std::span<const store::Promotion> promotions, PolicyKind kind);
// Loads the promoted checkpoints of `kind`. FAILED_PRECONDITION naming the roles not
// promoted yet; DATA_LOSS for a corrupted checkpoint; INVALID_ARGUMENT for checkpoints
// that do not fit together.
std::shared_ptr<const ServedPolicy> load_promoted(store::Store& store,
                                                  std::span<const store::Promotion> promotions,
                                                  PolicyKind kind);

}  // namespace pnp::serving
