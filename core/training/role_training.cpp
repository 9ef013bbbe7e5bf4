#include "training/role_training.h"

#include <memory>
#include <optional>

#include "arm_sim/arm_env_factory.h"
#include "common/error.h"
#include "nn/gemm_path.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/expert_checkpoint.h"
#include "rl/learned_expert.h"
#include "rl/subtask_trainer.h"
#include "sim/scripted_expert.h"

namespace pnp::training {
namespace {

std::string role_at(std::size_t k) {
  return std::string(sim::subtask_name(sim::kAllSubtasks[k]));
}

// The expert a blob holds (checked to be of `role`), or the scripted one for no blob.
std::unique_ptr<sim::SubtaskPolicy> policy_from(const Blob& blob, const std::string& role,
                                                const std::string& field) {
  if (blob.empty()) return std::make_unique<sim::ScriptedPolicy>();
  return rl::learned_expert_from(rl::load_expert(blob), role, field);
}

rl::ExpertAlgorithm expert_algorithm(const TrainingSpec& spec) {
  if (spec.role == "e2e") return rl::ExpertAlgorithm::kEndToEnd;
  if (spec.algorithm == "bc") return rl::ExpertAlgorithm::kBcOnline;
  if (spec.algorithm == "bc_offline") return rl::ExpertAlgorithm::kBcOffline;
  return rl::ExpertAlgorithm::kDdpgHer;
}

std::unique_ptr<sim::EnvFactory> environments(const TrainingSpec& spec,
                                              const TrainingHooks& hooks) {
  if (hooks.environments) {
    return hooks.environments(spec.robot, spec.object, spec.world, spec.actuation);
  }
  return arm_sim::make_env_factory(spec.robot, spec.object, spec.world, spec.actuation);
}

TrainingOutcome train_expert(const TrainingSpec& spec, const TrainingInputs& inputs,
                             const TrainingHooks& hooks, const std::string& code_commit) {
  const bool end_to_end = spec.role == "e2e";
  const auto envs = environments(spec, hooks);
  std::optional<rl::LoadedExpert> init;
  if (!inputs.init.empty()) {
    init = rl::load_expert(inputs.init);
    if (init->meta.role != spec.role)
      throw_invalid_argument("init", "a checkpoint of role " + spec.role,
                             "role " + init->meta.role);
  }
  rl::SubtaskTrainingConfig config;
  config.algorithm = expert_algorithm(spec);
  config.subtask = end_to_end ? sim::Subtask::kRetract : sim::parse_subtask(spec.role, "role");
  config.seed = spec.seed;
  config.ddpg = effective_ddpg(spec);
  config.stop = spec.stop;
  config.init = init ? &*init : nullptr;
  config.threads = hooks.threads;
  config.control = hooks.control;
  std::array<std::unique_ptr<sim::SubtaskPolicy>, sim::kNumSubtasks> others;
  if (!end_to_end) {
    const auto own = static_cast<std::size_t>(config.subtask);
    for (std::size_t k = 0; k < others.size(); ++k) {
      if (k == own || inputs.experts[k].empty()) continue;
      const std::string field = (k < own ? "prefix[" : "successors[") + std::to_string(k) + "]";
      others[k] = policy_from(inputs.experts[k], role_at(k), field);
      (k < own ? config.prefix : config.successors)[k] = others[k].get();
    }
  }
  auto meta_at = [&](long long steps, double success) {
    return rl::ExpertMeta{spec.role,
                          spec.algorithm,
                          std::string(sim::robot_name(spec.robot)),
                          std::string(sim::object_name(spec.object)),
                          std::string(sim::world_profile_name(spec.world)),
                          config.ddpg.hidden,
                          config.ddpg.hidden_activation,
                          config.ddpg.learn_gripper,
                          config.ddpg.clip_obs,
                          config.ddpg.norm_clip,
                          config.ddpg.norm_std_floor,
                          steps,
                          success,
                          spec.seed,
                          code_commit,
                          std::string(nn::gemm_path_name(nn::active_gemm_path())),
                          std::string(sim::actuation_name(spec.actuation)),
                          std::string(sim::gripper_script_name(config.ddpg.gripper_script))};
  };
  auto save = [&](const rl::DdpgHerAgent& agent, long long steps, double success) {
    return rl::save_expert(meta_at(steps, success), agent.actor(), &agent.critic(),
                           agent.observation_normalizer(), agent.goal_normalizer());
  };
  if (hooks.on_evaluation) {
    config.on_evaluation = [&](const rl::CurvePoint& p, const rl::DdpgHerAgent& agent) {
      hooks.on_evaluation(p, save(agent, p.env_steps, p.task_success));
    };
  }
  auto output = rl::train_subtask_expert(*envs, config, hooks.progress);
  TrainingOutcome out{std::move(output.result), {}};
  out.checkpoint = save(*output.agent, out.result.train_env_steps, out.result.final_success);
  return out;
}

TrainingOutcome train_hlc(const TrainingSpec& spec, const TrainingInputs& inputs,
                          const TrainingHooks& hooks, const std::string& code_commit) {
  const auto envs = environments(spec, hooks);
  std::array<std::unique_ptr<sim::SubtaskPolicy>, sim::kNumSubtasks> experts;
  for (std::size_t k = 0; k < experts.size(); ++k)
    experts[k] = policy_from(inputs.experts[k], role_at(k), "experts[" + std::to_string(k) + "]");
  std::optional<rl::LoadedChoreographer> init;
  if (!inputs.init.empty()) init = rl::load_choreographer(inputs.init);
  rl::HlcTrainingConfig config;
  config.seed = spec.seed;
  config.a3c = spec.a3c;
  config.stop = spec.stop;
  config.init = init ? &init->net : nullptr;
  config.eval_threads = hooks.threads;
  config.control = hooks.control;
  auto meta_at = [&](long long steps, double success) {
    return rl::ChoreographerMeta{std::string(sim::robot_name(spec.robot)),
                                 std::string(sim::object_name(spec.object)),
                                 std::string(sim::world_profile_name(spec.world)),
                                 spec.a3c.network,
                                 steps,
                                 success,
                                 spec.seed,
                                 code_commit,
                                 std::string(nn::gemm_path_name(nn::active_gemm_path())),
                                 std::string(sim::actuation_name(spec.actuation))};
  };
  if (hooks.on_evaluation) {
    config.on_evaluation = [&](const rl::CurvePoint& p, rl::ChoreographerNet& net) {
      hooks.on_evaluation(p, rl::save_choreographer(meta_at(p.env_steps, p.task_success), net));
    };
  }
  auto output = rl::train_choreographer(
      *envs, {experts[0].get(), experts[1].get(), experts[2].get()}, config, hooks.progress);
  TrainingOutcome out{std::move(output.result), {}};
  out.checkpoint = rl::save_choreographer(
      meta_at(out.result.train_env_steps, out.result.final_success), *output.net);
  return out;
}

}  // namespace

TrainingOutcome train_role(const TrainingSpec& spec, const TrainingInputs& inputs,
                           const TrainingHooks& hooks, const std::string& code_commit) {
  spec.validate();
  return spec.role == "hlc" ? train_hlc(spec, inputs, hooks, code_commit)
                            : train_expert(spec, inputs, hooks, code_commit);
}

}  // namespace pnp::training
