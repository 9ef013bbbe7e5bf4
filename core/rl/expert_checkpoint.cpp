#include "rl/expert_checkpoint.h"

#include <nlohmann/json.hpp>

#include "common/error.h"
#include "nn/checkpoint_io.h"
#include "nn/flat_ops.h"

namespace pnp::rl {
namespace {

constexpr int kAct = sim::kActionSize;

void save_normalizer(nn::CheckpointWriter& w, const std::string& name, const nn::Normalizer& n) {
  w.add_doubles(name + ".sum", n.sums());
  w.add_doubles(name + ".sumsq", n.sums_of_squares());
  const double count = n.count();
  w.add_doubles(name + ".count", std::span<const double>(&count, 1));
}

nn::Normalizer load_normalizer(const nn::CheckpointReader& r, const std::string& name, int size,
                               const ExpertMeta& meta) {
  nn::Normalizer n(size, meta.norm_clip, meta.norm_std_floor);
  const auto sums = r.doubles(name + ".sum", static_cast<std::size_t>(size));
  const auto sumsq = r.doubles(name + ".sumsq", static_cast<std::size_t>(size));
  const auto count = r.doubles(name + ".count", 1);
  n.restore(sums, sumsq, count[0]);
  return n;
}

}  // namespace

std::vector<std::uint8_t> save_expert(const ExpertMeta& meta, const nn::Mlp& actor,
                                      const nn::Mlp* critic, const nn::Normalizer& obs_norm,
                                      const nn::Normalizer& goal_norm) {
  const nlohmann::json j = {{"kind", "subtask_expert"},
                            {"role", meta.role},
                            {"algorithm", meta.algorithm},
                            {"robot", meta.robot},
                            {"object", meta.object},
                            {"hidden", meta.hidden},
                            {"learn_gripper", meta.learn_gripper},
                            {"clip_obs", meta.clip_obs},
                            {"norm_clip", meta.norm_clip},
                            {"norm_std_floor", meta.norm_std_floor},
                            {"train_env_steps", meta.train_env_steps},
                            {"eval_success", meta.eval_success},
                            {"seed", meta.seed},
                            {"code_commit", meta.code_commit},
                            {"has_critic", critic != nullptr}};
  nn::CheckpointWriter w;
  w.add_text("meta", j.dump());
  w.add_floats("actor", actor.params());
  if (critic) w.add_floats("critic", critic->params());
  save_normalizer(w, "obs_norm", obs_norm);
  save_normalizer(w, "goal_norm", goal_norm);
  return w.finish();
}

LoadedExpert load_expert(std::span<const std::uint8_t> bytes) {
  const nn::CheckpointReader r(bytes);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(r.text("meta"));
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::kDataLoss, std::string("checkpoint: unreadable metadata: ") + e.what());
  }
  if (j.value("kind", "") != "subtask_expert") {
    throw_invalid_argument("checkpoint kind", "subtask_expert", "\"" + j.value("kind", "") + "\"");
  }
  ExpertMeta meta;
  try {
    meta.role = j.at("role");
    meta.algorithm = j.at("algorithm");
    meta.robot = j.at("robot");
    meta.object = j.at("object");
    meta.hidden = j.at("hidden").get<std::vector<int>>();
    meta.learn_gripper = j.at("learn_gripper");
    meta.clip_obs = j.at("clip_obs");
    meta.norm_clip = j.at("norm_clip");
    meta.norm_std_floor = j.at("norm_std_floor");
    meta.train_env_steps = j.at("train_env_steps");
    meta.eval_success = j.at("eval_success");
    meta.seed = j.at("seed");
    meta.code_commit = j.value("code_commit", "");
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::kDataLoss, std::string("checkpoint: incomplete metadata: ") + e.what());
  }
  nn::Mlp actor({kPolicyInputs, meta.hidden, kAct, nn::Activation::kReLU, nn::Activation::kTanh});
  nn::copy_into(actor.params(), r.floats("actor", actor.params().size()));
  std::optional<nn::Mlp> critic;
  if (j.value("has_critic", false)) {
    critic.emplace(nn::MlpSpec{kPolicyInputs + kAct, meta.hidden, 1, nn::Activation::kReLU,
                               nn::Activation::kNone});
    nn::copy_into(critic->params(), r.floats("critic", critic->params().size()));
  }
  auto obs_norm = load_normalizer(r, "obs_norm", sim::kObservationSize, meta);
  auto goal_norm = load_normalizer(r, "goal_norm", sim::kGoalSize, meta);
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
