#include "tools/common/training_json.h"

namespace pnp::tools {

nlohmann::json curve_json(const std::vector<rl::CurvePoint>& curve) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : curve) {
    out.push_back({{"env_steps", p.env_steps},
                   {"episodes", p.episodes},
                   {"wall_s", p.wall_s},
                   {"task_success", p.task_success},
                   {"subtask_success", p.subtask_success},
                   {"subtask_mean_steps", p.subtask_mean_steps},
                   {"sampled_success", p.sampled_success},
                   {"detail", p.detail},
                   {"critic_loss", p.critic_loss},
                   {"actor_loss", p.actor_loss},
                   {"updates", p.updates}});
  }
  return out;
}

nlohmann::json result_json(const rl::TrainingResult& r) {
  return {
      {"reached", r.reached},
      {"steps_to_target", r.reached ? nlohmann::json(r.steps_to_target) : nlohmann::json(nullptr)},
      {"final_success", r.final_success},
      {"train_env_steps", r.train_env_steps},
      {"train_episodes", r.train_episodes},
      {"eval_steps", r.eval_env_steps},
      {"wall_s", r.wall_s},
      {"eval_wall_s", r.eval_wall_s},
      {"curve", curve_json(r.curve)}};
}

nlohmann::json ddpg_config_json(const rl::DdpgHerConfig& c) {
  return {{"hidden", c.hidden},
          {"actor_learning_rate", c.actor_learning_rate},
          {"critic_learning_rate", c.critic_learning_rate},
          {"gamma", c.gamma},
          {"polyak", c.polyak},
          {"batch_size", c.batch_size},
          {"buffer_size", c.buffer_size},
          {"her_k", c.her_k},
          {"noise_eps", c.noise_eps},
          {"random_eps", c.random_eps},
          {"random_gripper", c.random_gripper},
          {"action_l2", c.action_l2},
          {"episodes_per_cycle", c.episodes_per_cycle},
          {"updates_per_cycle", c.updates_per_cycle},
          {"updates_per_transition", c.updates_per_transition},
          {"learn_gripper", c.learn_gripper},
          {"demo_episodes", c.demo_episodes},
          {"demo_pretrain_updates", c.demo_pretrain_updates},
          {"demo_bc_weight", c.demo_bc_weight},
          {"demo_batch_size", c.demo_batch_size}};
}

void print_progress(std::FILE* out, const std::string& role, const rl::CurvePoint& p) {
  std::fprintf(out, "%-10s steps %7lld  episodes %6lld  success %.2f  ", role.c_str(), p.env_steps,
               p.episodes, p.task_success);
  if (p.detail.empty()) {  // a subtask expert or end-to-end policy
    std::fprintf(out, "subtask %.2f (%4.1f steps)  critic %.4f", p.subtask_success,
                 p.subtask_mean_steps, p.critic_loss);
  } else {  // the choreographer
    std::fprintf(out, "sampled %.2f  greedy %s", p.sampled_success, p.detail.c_str());
  }
  std::fprintf(out, "  wall %6.1fs\n", p.wall_s);
}

}  // namespace pnp::tools
