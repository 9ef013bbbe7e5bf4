#include "training/training_json.h"

namespace pnp::training {

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
                   {"stop_score", p.stop_score},
                   {"detail", p.detail},
                   {"critic_loss", p.critic_loss},
                   {"actor_loss", p.actor_loss},
                   {"updates", p.updates}});
  }
  return out;
}

nlohmann::json breakdown_json(const WallBreakdown& b) {
  return {{"rollout_s", b.rollout_s}, {"update_s", b.update_s}, {"eval_s", b.eval_s},
          {"report_s", b.report_s},   {"other_s", b.other_s},   {"total_s", b.total_s}};
}

nlohmann::json result_json(const rl::TrainingResult& r) {
  return {
      {"reached", r.reached},
      {"cancelled", r.cancelled},
      {"steps_to_target", r.reached ? nlohmann::json(r.steps_to_target) : nlohmann::json(nullptr)},
      {"final_success", r.final_success},
      {"final_score", r.final_score},
      {"train_env_steps", r.train_env_steps},
      {"train_episodes", r.train_episodes},
      {"eval_steps", r.eval_env_steps},
      {"wall_s", r.wall_s},
      {"eval_wall_s", r.eval_wall_s},
      {"wall_breakdown", breakdown_json(r.breakdown)},
      {"curve", curve_json(r.curve)}};
}

}  // namespace pnp::training
