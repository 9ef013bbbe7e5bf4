#include "rl/expert_checkpoint.h"

#include <nlohmann/json.hpp>

#include "common/error.h"
#include "nn/checkpoint_io.h"
#include "nn/flat_ops.h"
#include "rl/checkpoint_sections.h"
#include "rl/network_limits.h"

namespace pnp::rl {
namespace {

constexpr int kAct = sim::kActionSize;
constexpr const char* kKind = "subtask_expert";

}  // namespace

std::vector<std::uint8_t> save_expert(const ExpertMeta& meta, const nn::Mlp& actor,
                                      const nn::Mlp* critic, const nn::Normalizer& obs_norm,
                                      const nn::Normalizer& goal_norm) {
  nlohmann::json j = {
      {"kind", kKind},
      {"role", meta.role},
      {"algorithm", meta.algorithm},
      {"gripper_script", meta.gripper_script},
      {"hidden", meta.hidden},
      {"hidden_activation", std::string(nn::activation_name(meta.hidden_activation))},
      {"learn_gripper", meta.learn_gripper},
      {"clip_obs", meta.clip_obs},
      {"norm_clip", meta.norm_clip},
      {"norm_std_floor", meta.norm_std_floor},
      {"has_critic", critic != nullptr}};
  write_provenance(meta, j);
  nn::CheckpointWriter w;
  write_meta(w, j);
  w.add_floats("actor", actor.params());
  if (critic) w.add_floats("critic", critic->params());
  write_normalizer(w, "obs_norm", obs_norm);
  write_normalizer(w, "goal_norm", goal_norm);
  return w.finish();
}

std::optional<sim::GripperScript> scripted_gripper_of(const ExpertMeta& meta) {
  if (meta.learn_gripper) return std::nullopt;
  return sim::parse_gripper_script(meta.gripper_script, "checkpoint gripper_script");
}

LoadedExpert load_expert(std::span<const std::uint8_t> bytes) {
  const nn::CheckpointReader r(bytes);
  const nlohmann::json j = read_meta(r, kKind);
  ExpertMeta meta = parse_meta(j, [](const nlohmann::json& m) {
    ExpertMeta out;
    out.role = m.at("role");
    out.algorithm = m.at("algorithm");
    read_provenance(m, out);
    out.gripper_script = m.value("gripper_script", "grasp_rule");
    sim::parse_gripper_script(out.gripper_script, "checkpoint gripper_script");
    out.hidden = m.at("hidden").get<std::vector<int>>();
    // Checkpoints written before the field existed are ReLU networks.
    const auto activation = m.find("hidden_activation");
    out.hidden_activation = activation == m.end()
                                ? nn::Activation::kReLU
                                : nn::parse_activation(activation->get_ref<const std::string&>(),
                                                       "checkpoint hidden_activation");
    out.learn_gripper = m.at("learn_gripper");
    out.clip_obs = m.at("clip_obs");
    out.norm_clip = m.at("norm_clip");
    out.norm_std_floor = m.at("norm_std_floor");
    return out;
  });
  // Bounded, and each section's size checked, before anything is allocated: the file's own
  // metadata sizes the networks (the critic, observation, goal and action in, is the larger).
  check_layer_widths("checkpoint hidden", meta.hidden, kPolicyInputs + kAct, 1);
  const nn::MlpSpec actor_spec{kPolicyInputs, meta.hidden, kAct, meta.hidden_activation,
                               nn::Activation::kTanh};
  const nn::MlpSpec critic_spec{kPolicyInputs + kAct, meta.hidden, 1, meta.hidden_activation,
                                nn::Activation::kNone};
  const bool has_critic = j.value("has_critic", false);
  require_float_section(r, "actor", nn::Mlp::flat_size(actor_spec));
  if (has_critic) require_float_section(r, "critic", nn::Mlp::flat_size(critic_spec));
  nn::Mlp actor(actor_spec);
  nn::copy_into(actor.params(), r.floats("actor", actor.params().size()));
  std::optional<nn::Mlp> critic;
  if (has_critic) {
    critic.emplace(critic_spec);
    nn::copy_into(critic->params(), r.floats("critic", critic->params().size()));
  }
  nn::Normalizer obs_norm(sim::kObservationSize, meta.norm_clip, meta.norm_std_floor);
  nn::Normalizer goal_norm(sim::kGoalSize, meta.norm_clip, meta.norm_std_floor);
  read_normalizer(r, "obs_norm", obs_norm);
  read_normalizer(r, "goal_norm", goal_norm);
  return {std::move(meta), std::move(actor), std::move(critic), std::move(obs_norm),
          std::move(goal_norm)};
}

void restore_agent(DdpgHerAgent& agent, const LoadedExpert& expert) {
  if (agent.actor().spec() != expert.actor.spec()) {
    throw_invalid_argument("--init", "a checkpoint with the same network widths as this run",
                           "a different actor shape");
  }
  nn::copy_into(agent.actor().params(), expert.actor.params());
  if (expert.critic) nn::copy_into(agent.critic().params(), expert.critic->params());
  agent.observation_normalizer().restore(expert.observation_normalizer.sums(),
                                         expert.observation_normalizer.sums_of_squares(),
                                         expert.observation_normalizer.count());
  agent.goal_normalizer().restore(expert.goal_normalizer.sums(),
                                  expert.goal_normalizer.sums_of_squares(),
                                  expert.goal_normalizer.count());
  agent.sync_targets();
}

}  // namespace pnp::rl
