#include "serving/served_hierarchy.h"

#include "common/error.h"
#include "rl/hierarchy_controller.h"
#include "serving/batched_expert.h"

namespace pnp::serving {
namespace {

constexpr std::array<const char*, sim::kNumSubtasks> kExpertRoles{"approach", "manipulate",
                                                                  "retract"};

// A HierarchyController answering as a PolicyController, with the ids that answered.
class HierarchyPolicyController final : public PolicyController {
 public:
  HierarchyPolicyController(std::unique_ptr<rl::HierarchyController> controller, ServedIds ids)
      : controller_(std::move(controller)), ids_(ids) {}

  void reset(int episode_steps) override { controller_->reset(episode_steps); }

  Decision act(const sim::Observation& observation, const sim::Goal& episode_goal) override {
    const rl::HierarchyController::Decision h = controller_->act(observation, episode_goal);
    Decision d;
    d.subtask = h.subtask;
    d.action = h.action;
    d.value = h.value;
    d.probabilities = h.probabilities;
    d.decided = h.decided;
    d.placed = h.placed;
    d.choreographer_checkpoint_id = ids_.choreographer;
    d.expert_checkpoint_id = ids_.experts[static_cast<std::size_t>(h.subtask)];
    return d;
  }

  int steps() const override { return controller_->steps(); }
  int episode_steps() const override { return controller_->episode_steps(); }

 private:
  std::unique_ptr<rl::HierarchyController> controller_;
  ServedIds ids_;
};

}  // namespace

std::optional<ServedIds> ServedHierarchy::promoted_ids(
    std::span<const store::Promotion> promotions) {
  const auto find = [&](std::string_view role) -> std::optional<std::int64_t> {
    for (const auto& p : promotions)
      if (p.role == role) return p.checkpoint_id;
    return std::nullopt;
  };
  ServedIds ids;
  for (std::size_t k = 0; k < kExpertRoles.size(); ++k) {
    const auto id = find(kExpertRoles[k]);
    if (!id) return std::nullopt;
    ids.experts[k] = *id;
  }
  const auto hlc = find("hlc");
  if (!hlc) return std::nullopt;
  ids.choreographer = *hlc;
  return ids;
}

std::shared_ptr<const ServedHierarchy> ServedHierarchy::load_promoted(
    store::Store& store, std::span<const store::Promotion> promotions) {
  const auto promoted = promoted_ids(promotions);
  if (!promoted) {
    std::string missing;
    for (const char* role : {"approach", "manipulate", "retract", "hlc"}) {
      bool found = false;
      for (const auto& p : promotions) found = found || p.role == role;
      if (!found) missing += (missing.empty() ? "" : ", ") + std::string(role);
    }
    throw Error(ErrorCode::kFailedPrecondition,
                "no promoted checkpoint for " + missing + ": promote one per role first");
  }
  const ServedIds ids = *promoted;
  std::array<rl::LoadedExpert, sim::kNumSubtasks> experts{
      rl::load_expert(store.load_checkpoint(ids.experts[0]).blob),
      rl::load_expert(store.load_checkpoint(ids.experts[1]).blob),
      rl::load_expert(store.load_checkpoint(ids.experts[2]).blob)};
  auto choreographer = rl::load_choreographer(store.load_checkpoint(ids.choreographer).blob);
  return std::make_shared<const ServedHierarchy>(std::move(choreographer), std::move(experts), ids);
}

ServedHierarchy::ServedHierarchy(rl::LoadedChoreographer choreographer,
                                 std::array<rl::LoadedExpert, sim::kNumSubtasks> experts,
                                 ServedIds ids)
    : choreographer_(std::move(choreographer)),
      experts_(std::move(experts)),
      ids_(ids),
      robot_(sim::parse_robot(choreographer_.meta.robot, "choreographer checkpoint robot")),
      // The shape the hierarchy handles is the retract expert's: only retract (with its
      // gripper closure) is fine-tuned for a new shape, the rest may come from another.
      object_(sim::parse_object(experts_[2].meta.object, "retract checkpoint object")),
      world_(sim::parse_world_profile(choreographer_.meta.world, "choreographer checkpoint world")),
      actuation_(sim::parse_actuation(choreographer_.meta.actuation,
                                      "choreographer checkpoint actuation")) {
  for (std::size_t k = 0; k < experts_.size(); ++k) {
    const auto& meta = experts_[k].meta;
    if (meta.role != kExpertRoles[k]) {
      throw_invalid_argument(std::string(kExpertRoles[k]) + " checkpoint",
                             std::string("role ") + kExpertRoles[k], "role " + meta.role);
    }
    if (meta.robot != choreographer_.meta.robot) {
      throw_invalid_argument(std::string(kExpertRoles[k]) + " checkpoint",
                             "the choreographer's robot (" + choreographer_.meta.robot + ")",
                             meta.robot);
    }
    // One component trained on the mocap hand makes the whole a mocap-trained policy.
    if (sim::parse_actuation(meta.actuation,
                             std::string(kExpertRoles[k]) + " checkpoint actuation") ==
        sim::Actuation::kMocap) {
      actuation_ = sim::Actuation::kMocap;
    }
  }
  for (std::size_t k = 0; k < experts_.size(); ++k) {
    const auto& e = experts_[k];
    batchers_[k] = std::make_shared<ActorBatcher>(e.actor, e.observation_normalizer,
                                                  e.goal_normalizer, e.meta.clip_obs);
  }
  warm_up();  // fail here, not in the first request, if anything is wrong
}

std::unique_ptr<PolicyController> ServedHierarchy::make_controller() const {
  rl::HierarchyController::Experts experts;
  for (std::size_t k = 0; k < experts.size(); ++k) {
    experts[k] =
        std::make_unique<BatchedExpert>(batchers_[k], rl::scripted_gripper_of(experts_[k].meta));
  }
  return std::make_unique<HierarchyPolicyController>(
      // Caps for the episode the policy was trained in; acquire() resets them to the client's.
      std::make_unique<rl::HierarchyController>(choreographer_.net, std::move(experts),
                                                2 * sim::object_spec(object_).half_width_m,
                                                sim::episode_steps(actuation_)),
      ids_);
}

std::vector<std::int64_t> ServedHierarchy::checkpoint_ids() const {
  return {ids_.experts[0], ids_.experts[1], ids_.experts[2], ids_.choreographer};
}

std::vector<BatchStats> ServedHierarchy::batch_stats() const {
  std::vector<BatchStats> stats;
  stats.reserve(batchers_.size());
  for (const auto& b : batchers_) stats.push_back(b->stats());
  return stats;
}

}  // namespace pnp::serving
