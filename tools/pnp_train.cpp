// pnp-train: trains one role locally (no services) and prints the learning curve.
//   --role approach|manipulate|retract  --algo ddpg_her|bc  (subtask experts)
//   --role e2e --algo ddpg_her                                (end-to-end baseline)
//   --role hlc --algo a3c                                     (the choreographer)
// Writes DIR/<role>.ckpt and DIR/<role>.json (role hlc included).

#include <array>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "build_info.h"
#include "common/error.h"
#include "common/validate.h"
#include "nn/checkpoint_io.h"
#include "rl/a3c_trainer.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/expert_checkpoint.h"
#include "rl/learned_expert.h"
#include "rl/subtask_trainer.h"
#include "tools/common/cli.h"
#include "tools/common/training_json.h"

namespace {

using namespace pnp;

struct Options {
  std::string role = "approach", algo = "ddpg_her", robot = "fetch", object = "block",
              out = "runs/latest";
  std::string init, experts, prefix = "scripted";
  std::uint64_t seed = 0;
  bool json = false, quiet = false, scripted_gripper = false;
  std::size_t threads = 0;
  rl::DdpgHerConfig ddpg;
  rl::A3cConfig a3c;
  rl::StopRule stop;
};

void add_ddpg_options(CLI::App& app, Options& o) {
  app.add_option("--hidden", o.ddpg.hidden, "hidden widths of actor and critic")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--batch-size", o.ddpg.batch_size)->capture_default_str();
  app.add_option("--buffer-size", o.ddpg.buffer_size)->capture_default_str();
  app.add_option("--actor-lr", o.ddpg.actor_learning_rate)->capture_default_str();
  app.add_option("--critic-lr", o.ddpg.critic_learning_rate)->capture_default_str();
  app.add_option("--gamma", o.ddpg.gamma)->capture_default_str();
  app.add_option("--polyak", o.ddpg.polyak)->capture_default_str();
  app.add_option("--her-k", o.ddpg.her_k)->capture_default_str();
  app.add_option("--noise-eps", o.ddpg.noise_eps)->capture_default_str();
  app.add_option("--random-eps", o.ddpg.random_eps)->capture_default_str();
  app.add_option("--action-l2", o.ddpg.action_l2)->capture_default_str();
  app.add_option("--episodes-per-cycle", o.ddpg.episodes_per_cycle)->capture_default_str();
  app.add_option("--updates-per-cycle", o.ddpg.updates_per_cycle)->capture_default_str();
  app.add_option("--updates-per-transition", o.ddpg.updates_per_transition,
                 "> 0: gradient steps per stored transition instead of --updates-per-cycle")
      ->capture_default_str();
  app.add_flag("--scripted-gripper", o.scripted_gripper,
               "keep the gripper command scripted (paper-faithful)");
  app.add_option("--demo-episodes", o.ddpg.demo_episodes,
                 "scripted demonstrations before exploring (counted)")
      ->capture_default_str();
  app.add_option("--demo-pretrain-updates", o.ddpg.demo_pretrain_updates)->capture_default_str();
  app.add_option("--demo-bc-weight", o.ddpg.demo_bc_weight,
                 "behaviour-cloning weight on demonstrations")
      ->capture_default_str();
}

void write_outputs(const Options& o, const std::vector<std::uint8_t>& checkpoint,
                   const nlohmann::json& summary) {
  std::filesystem::create_directories(o.out);
  nn::write_file_atomically(o.out + "/" + o.role + ".ckpt", checkpoint);
  const std::string text = summary.dump(2) + "\n";
  nn::write_file_atomically(o.out + "/" + o.role + ".json",
                            {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

// An expert for the choreographer or a prefix: "scripted", or a checkpoint path.
std::unique_ptr<sim::SubtaskPolicy> load_policy(const std::string& spec, const std::string& role,
                                                const std::string& field) {
  if (spec == "scripted") return std::make_unique<sim::ScriptedPolicy>();
  rl::LoadedExpert e = rl::load_expert(nn::read_file(spec));
  if (e.meta.role != role) {
    throw_invalid_argument(field, "a " + role + " checkpoint in that position",
                           "role " + e.meta.role);
  }
  return std::make_unique<rl::LearnedExpert>(
      rl::ActorSnapshot(e.actor, e.observation_normalizer, e.goal_normalizer, e.meta.clip_obs),
      e.meta.learn_gripper);
}

// The experts before `subtask`: --prefix scripted (the paper), chained (the checkpoints
// of the earlier roles in --out) or one comma-separated checkpoint or "scripted" each.
std::vector<std::string> prefix_specs(const Options& o, sim::Subtask subtask) {
  const auto count = static_cast<std::size_t>(subtask);
  std::vector<std::string> specs;
  if (o.prefix == "scripted" || o.prefix == "chained") {
    for (std::size_t k = 0; k < count; ++k) {
      specs.push_back(o.prefix == "scripted"
                          ? "scripted"
                          : o.out + "/" + std::string(sim::subtask_name(sim::kAllSubtasks[k])) +
                                ".ckpt");
    }
    return specs;
  }
  std::stringstream in(o.prefix);
  for (std::string item; std::getline(in, item, ',');) specs.push_back(item);
  if (specs.size() != count) {
    throw_invalid_argument("--prefix",
                           "scripted, chained, or " + std::to_string(count) +
                               " comma-separated checkpoints (or \"scripted\") for the subtasks "
                               "before " +
                               o.role,
                           "\"" + o.prefix + "\"");
  }
  return specs;
}

nlohmann::json train_expert(const Options& o) {
  const bool end_to_end = o.role == "e2e";
  const auto subtask = end_to_end ? sim::Subtask::kRetract : sim::parse_subtask(o.role, "--role");
  const auto robot = sim::parse_robot(o.robot, "--robot");
  const auto object = sim::parse_object(o.object, "--object");
  const auto world = sim::WorldModel::load(robot, object);
  std::optional<rl::LoadedExpert> init;
  if (!o.init.empty()) {
    init = rl::load_expert(nn::read_file(o.init));
    if (init->meta.role != o.role) {
      throw_invalid_argument("--init", "a checkpoint of role " + o.role, "role " + init->meta.role);
    }
  }
  rl::SubtaskTrainingConfig config;
  config.algorithm = end_to_end               ? rl::ExpertAlgorithm::kEndToEnd
                     : o.algo == "bc"         ? rl::ExpertAlgorithm::kBcOnline
                     : o.algo == "bc_offline" ? rl::ExpertAlgorithm::kBcOffline
                                              : rl::ExpertAlgorithm::kDdpgHer;
  config.subtask = subtask;
  config.seed = o.seed;
  config.ddpg = o.ddpg;
  config.ddpg.learn_gripper = !o.scripted_gripper || end_to_end;
  if (end_to_end) config.ddpg.random_gripper = true;  // the standard end-to-end setup
  config.stop = o.stop;
  config.threads = o.threads;
  config.init = init ? &*init : nullptr;
  const std::vector<std::string> prefix =
      end_to_end ? std::vector<std::string>{} : prefix_specs(o, subtask);
  std::array<std::unique_ptr<sim::SubtaskPolicy>, sim::kNumSubtasks> prefix_policies;
  for (std::size_t k = 0; k < prefix.size(); ++k) {
    if (prefix[k] == "scripted") continue;
    prefix_policies[k] =
        load_policy(prefix[k], std::string(sim::subtask_name(sim::kAllSubtasks[k])), "--prefix");
    config.prefix[k] = prefix_policies[k].get();
  }
  const auto output = rl::train_subtask_expert(world, config, [&](const rl::CurvePoint& p) {
    if (!o.quiet) tools::print_progress(stderr, o.role, p);
  });
  rl::ExpertMeta meta{o.role,
                      o.algo,
                      o.robot,
                      o.object,
                      config.ddpg.hidden,
                      config.ddpg.learn_gripper,
                      config.ddpg.clip_obs,
                      config.ddpg.norm_clip,
                      config.ddpg.norm_std_floor,
                      output.result.train_env_steps,
                      output.result.final_success,
                      o.seed,
                      kCodeCommit};
  nlohmann::json summary = tools::result_json(output.result);
  summary["role"] = o.role;
  summary["algo"] = o.algo;
  summary["robot"] = o.robot;
  summary["object"] = o.object;
  summary["seed"] = o.seed;
  summary["code_commit"] = kCodeCommit;
  summary["config"] = tools::ddpg_config_json(config.ddpg);
  summary["checkpoint"] = o.out + "/" + o.role + ".ckpt";
  if (init) summary["init"] = o.init;
  if (!end_to_end) summary["prefix"] = prefix;
  write_outputs(
      o,
      rl::save_expert(meta, output.agent->actor(), &output.agent->critic(),
                      output.agent->observation_normalizer(), output.agent->goal_normalizer()),
      summary);
  return summary;
}

nlohmann::json train_hlc(const Options& o) {
  const auto world = sim::WorldModel::load(sim::parse_robot(o.robot, "--robot"),
                                           sim::parse_object(o.object, "--object"));
  std::vector<std::string> specs;
  if (o.experts.empty()) {
    for (auto s : sim::kAllSubtasks)
      specs.push_back(o.out + "/" + std::string(sim::subtask_name(s)) + ".ckpt");
  } else {
    std::stringstream in(o.experts);
    for (std::string item; std::getline(in, item, ',');) specs.push_back(item);
    if (specs.size() != 3) {
      throw_invalid_argument("--experts", "three comma-separated checkpoints (or \"scripted\")",
                             std::to_string(specs.size()) + " items");
    }
  }
  std::array<std::unique_ptr<sim::SubtaskPolicy>, 3> experts;
  for (std::size_t k = 0; k < 3; ++k)
    experts[k] =
        load_policy(specs[k], std::string(sim::subtask_name(sim::kAllSubtasks[k])), "--experts");
  rl::HlcTrainingConfig config;
  config.seed = o.seed;
  config.a3c = o.a3c;
  config.stop = o.stop;
  config.eval_threads = o.threads;
  const auto output =
      rl::train_choreographer(world, {experts[0].get(), experts[1].get(), experts[2].get()}, config,
                              [&](const rl::CurvePoint& p) {
                                if (!o.quiet) tools::print_progress(stderr, "hlc", p);
                              });
  nlohmann::json summary = tools::result_json(output.result);
  summary["role"] = "hlc";
  summary["algo"] = "a3c";
  summary["robot"] = o.robot;
  summary["object"] = o.object;
  summary["seed"] = o.seed;
  summary["code_commit"] = kCodeCommit;
  summary["experts"] = specs;
  summary["config"] = {{"workers", o.a3c.workers},
                       {"learning_rate", o.a3c.learning_rate},
                       {"gamma", o.a3c.gamma},
                       {"gae_lambda", o.a3c.gae_lambda},
                       {"entropy_weight", o.a3c.entropy_weight},
                       {"value_weight", o.a3c.value_weight},
                       {"max_grad_norm", o.a3c.max_grad_norm},
                       {"trunk", o.a3c.network.trunk},
                       {"lstm", o.a3c.network.lstm}};
  summary["checkpoint"] = o.out + "/hlc.ckpt";
  const rl::ChoreographerMeta meta{o.robot,
                                   o.object,
                                   o.a3c.network,
                                   output.result.train_env_steps,
                                   output.result.final_success,
                                   o.seed,
                                   kCodeCommit};
  write_outputs(o, rl::save_choreographer(meta, *output.net), summary);
  return summary;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Train a subtask expert, the choreographer or a baseline, locally", "pnp-train"};
  Options o;
  app.add_option("--role", o.role, "approach, manipulate, retract, hlc or e2e")
      ->capture_default_str();
  app.add_option("--algo", o.algo, "ddpg_her, bc (online, DAgger-style), bc_offline or a3c")
      ->capture_default_str();
  app.add_option("--robot", o.robot)->capture_default_str();
  app.add_option("--object", o.object)->capture_default_str();
  app.add_option("--seed", o.seed)->capture_default_str();
  app.add_option("--max-steps", o.stop.max_steps, "training environment steps cap")
      ->capture_default_str();
  app.add_option("--target-success", o.stop.target_success, "task success to reach twice in a row")
      ->capture_default_str();
  app.add_option("--eval-interval", o.stop.eval_interval_steps,
                 "training steps between evaluations")
      ->capture_default_str();
  app.add_option("--eval-episodes", o.stop.eval_episodes)->capture_default_str();
  app.add_option("--out", o.out, "output directory for checkpoints")->capture_default_str();
  app.add_option("--init", o.init, "checkpoint to fine-tune from");
  app.add_option("--experts", o.experts, "hlc: approach,manipulate,retract checkpoints");
  app.add_option("--prefix", o.prefix,
                 "experts before this subtask: scripted, chained (earlier checkpoints in --out) "
                 "or comma-separated checkpoints")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "worker threads (0: all cores)");
  app.add_flag("--json", o.json, "print the result as one JSON object");
  app.add_flag("--quiet", o.quiet, "no progress lines on stderr");
  add_ddpg_options(app, o);
  app.add_option("--workers", o.a3c.workers,
                 "hlc: A3C workers (the result depends on this, not on threads)")
      ->capture_default_str();
  app.add_option("--hlc-lr", o.a3c.learning_rate)->capture_default_str();
  app.add_option("--entropy", o.a3c.entropy_weight)->capture_default_str();
  app.add_option("--hlc-gamma", o.a3c.gamma, "hlc: discount per environment step")
      ->capture_default_str();
  return tools::run_tool(app, argc, argv, [&] {
    nlohmann::json summary;
    const bool expert = o.role == "approach" || o.role == "manipulate" || o.role == "retract";
    if (o.role == "e2e") {
      if (o.algo != "ddpg_her") {
        throw_invalid_argument("--algo", "ddpg_her for the end-to-end baseline",
                               "\"" + o.algo + "\"");
      }
      summary = train_expert(o);
    } else if (expert) {
      if (o.algo != "ddpg_her" && o.algo != "bc" && o.algo != "bc_offline") {
        throw_invalid_argument("--algo", "one of ddpg_her, bc, bc_offline for a subtask expert",
                               "\"" + o.algo + "\"");
      }
      summary = train_expert(o);
    } else if (o.role == "hlc") {
      if (o.algo != "a3c")
        throw_invalid_argument("--algo", "a3c for the choreographer", "\"" + o.algo + "\"");
      summary = train_hlc(o);
    } else {
      throw_invalid_argument("--role", "one of approach, manipulate, retract, hlc, e2e",
                             "\"" + o.role + "\"");
    }
    if (o.json) {
      std::cout << summary.dump() << "\n";
    } else {
      std::cout << summary.dump(2) << "\n";
    }
  });
}
