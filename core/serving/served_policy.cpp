#include "serving/served_policy.h"

#include "common/error.h"
#include "serving/served_end_to_end.h"
#include "serving/served_hierarchy.h"
#include "sim/world_layout.h"

namespace pnp::serving {

std::string_view policy_kind_name(PolicyKind kind) {
  return kind == PolicyKind::kEndToEnd ? "e2e" : "hierarchy";
}

PolicyKind parse_policy_kind(std::string_view name, std::string_view field) {
  if (name == "hierarchy") return PolicyKind::kHierarchy;
  if (name == "e2e") return PolicyKind::kEndToEnd;
  throw_invalid_argument(field, "hierarchy or e2e", "\"" + std::string(name) + "\"");
}

std::vector<std::string> served_roles(PolicyKind kind) {
  if (kind == PolicyKind::kEndToEnd) return {"e2e"};
  return {"approach", "manipulate", "retract", "hlc"};
}

std::vector<std::string> batched_actors(PolicyKind kind) {
  if (kind == PolicyKind::kEndToEnd) return {"e2e"};
  return {"approach", "manipulate", "retract"};
}

ServedPolicy::Lease ServedPolicy::acquire(int episode_steps) const {
  if (episode_steps < 0 || episode_steps > sim::layout::kMaxEpisodeSteps) {
    throw_invalid_argument(
        "episode_steps", "0 (the policy's own) to " + std::to_string(sim::layout::kMaxEpisodeSteps),
        std::to_string(episode_steps));
  }
  std::unique_ptr<PolicyController> controller;
  {
    std::lock_guard lock(pool_mutex_);
    if (!pool_.empty()) {
      controller = std::move(pool_.back());
      pool_.pop_back();
    }
  }
  if (!controller) controller = make_controller();
  controller->reset(episode_steps > 0 ? episode_steps : sim::episode_steps(actuation()));
  return Lease(shared_from_this(), std::move(controller));
}

void ServedPolicy::give_back(std::unique_ptr<PolicyController> controller) const {
  std::lock_guard lock(pool_mutex_);
  pool_.push_back(std::move(controller));
}

ServedPolicy::Lease::Lease(std::shared_ptr<const ServedPolicy> owner,
                           std::unique_ptr<PolicyController> controller)
    : owner_(std::move(owner)), controller_(std::move(controller)) {}

ServedPolicy::Lease::~Lease() {
  if (owner_ && controller_) owner_->give_back(std::move(controller_));
}

std::optional<std::vector<std::int64_t>> promoted_checkpoint_ids(
    std::span<const store::Promotion> promotions, PolicyKind kind) {
  if (kind == PolicyKind::kEndToEnd) {
    const auto id = ServedEndToEnd::promoted_id(promotions);
    if (!id) return std::nullopt;
    return std::vector<std::int64_t>{*id};
  }
  const auto ids = ServedHierarchy::promoted_ids(promotions);
  if (!ids) return std::nullopt;
  return std::vector<std::int64_t>{ids->experts[0], ids->experts[1], ids->experts[2],
                                   ids->choreographer};
}

std::shared_ptr<const ServedPolicy> load_promoted(store::Store& store,
                                                  std::span<const store::Promotion> promotions,
                                                  PolicyKind kind) {
  if (kind == PolicyKind::kEndToEnd) return ServedEndToEnd::load_promoted(store, promotions);
  return ServedHierarchy::load_promoted(store, promotions);
}

}  // namespace pnp::serving
