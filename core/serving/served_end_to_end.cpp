#include "serving/served_end_to_end.h"

#include <string>

#include "common/error.h"
#include "common/validate.h"
#include "serving/batched_expert.h"

namespace pnp::serving {
namespace {

// One episode of the end-to-end actor, as rl::evaluate_end_to_end runs it: the episode
// goal, the retract subtask (whose scripted gripper stands in when the checkpoint did not
// learn its own), and every step answered by the actor.
class EndToEndController final : public PolicyController {
 public:
  EndToEndController(std::shared_ptr<ActorBatcher> batcher,
                     std::optional<sim::GripperScript> scripted_gripper, double object_width_m,
                     std::int64_t checkpoint_id)
      : actor_(std::move(batcher), scripted_gripper),
        object_width_m_(object_width_m),
        checkpoint_id_(checkpoint_id) {}

  // No subtasks to cap: the length is only reported back.
  void reset(int episode_steps) override {
    steps_ = 0;
    episode_steps_ = episode_steps;
  }

  Decision act(const sim::Observation& observation, const sim::Goal& episode_goal) override {
    require_finite_vector({observation.data(), sim::kObservationSize}, sim::kObservationSize,
                          "observation");
    require_finite_vector({episode_goal.data(), sim::kGoalSize}, sim::kGoalSize, "goal");
    const sim::TaskState state = sim::TaskState::from(observation, episode_goal, object_width_m_);
    ++steps_;
    Decision d;
    d.action = actor_.act(sim::Subtask::kRetract, observation, episode_goal, state);
    d.expert_checkpoint_id = checkpoint_id_;
    return d;
  }

  int steps() const override { return steps_; }
  int episode_steps() const override { return episode_steps_; }

 private:
  BatchedExpert actor_;
  double object_width_m_;
  std::int64_t checkpoint_id_;
  int steps_ = 0;
  int episode_steps_ = 0;
};

}  // namespace

std::optional<std::int64_t> ServedEndToEnd::promoted_id(
    std::span<const store::Promotion> promotions) {
  for (const auto& p : promotions)
    if (p.role == "e2e") return p.checkpoint_id;
  return std::nullopt;
}

std::shared_ptr<const ServedEndToEnd> ServedEndToEnd::load_promoted(
    store::Store& store, std::span<const store::Promotion> promotions) {
  const auto id = promoted_id(promotions);
  if (!id) {
    throw Error(ErrorCode::kFailedPrecondition,
                "no promoted checkpoint for e2e: promote an end-to-end checkpoint first");
  }
  return std::make_shared<const ServedEndToEnd>(rl::load_expert(store.load_checkpoint(*id).blob),
                                                *id);
}

ServedEndToEnd::ServedEndToEnd(rl::LoadedExpert policy, std::int64_t checkpoint_id)
    : policy_(std::move(policy)),
      checkpoint_id_(checkpoint_id),
      robot_(sim::parse_robot(policy_.meta.robot, "e2e checkpoint robot")),
      object_(sim::parse_object(policy_.meta.object, "e2e checkpoint object")),
      world_(sim::parse_world_profile(policy_.meta.world, "e2e checkpoint world")),
      actuation_(sim::parse_actuation(policy_.meta.actuation, "e2e checkpoint actuation")) {
  if (policy_.meta.role != "e2e") {
    throw_invalid_argument("e2e checkpoint " + std::to_string(checkpoint_id), "role e2e",
                           "role " + policy_.meta.role);
  }
  if (policy_.meta.algorithm != "ddpg_her") {
    throw_invalid_argument("e2e checkpoint " + std::to_string(checkpoint_id), "algorithm ddpg_her",
                           "algorithm " + policy_.meta.algorithm);
  }
  batcher_ = std::make_shared<ActorBatcher>(policy_.actor, policy_.observation_normalizer,
                                            policy_.goal_normalizer, policy_.meta.clip_obs);
  warm_up();
}

std::unique_ptr<PolicyController> ServedEndToEnd::make_controller() const {
  return std::make_unique<EndToEndController>(batcher_, rl::scripted_gripper_of(policy_.meta),
                                              2 * sim::object_spec(object_).half_width_m,
                                              checkpoint_id_);
}

}  // namespace pnp::serving
