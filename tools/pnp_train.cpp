// pnp-train: trains one role locally (no services) and prints the learning curve.
//   --role approach|manipulate|retract  --algo ddpg_her|bc  (subtask experts)
//   --role e2e --algo ddpg_her                                (end-to-end baseline)
//   --role hlc --algo a3c                                     (the choreographer)
// Writes DIR/<role>.ckpt and DIR/<role>.json (role hlc included).

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "build_info.h"
#include "common/error.h"
#include "common/seed_flag.h"
#include "nn/checkpoint_io.h"
#include "nn/gemm_path.h"
#include "tools/common/cli.h"
#include "tools/common/preset_option.h"
#include "tools/common/progress_line.h"
#include "training/preset.h"
#include "training/role_training.h"
#include "training/training_json.h"

namespace {

using namespace pnp;

struct Options {
  training::TrainingSpec spec;
  std::string robot = "fetch", object = "block", out = "runs/latest";
  std::string world{sim::world_profile_name(sim::kDefaultWorldProfile)};
  std::string actuation = "default";  // the robot's own (sim/actuation.h)
  std::string gripper_script;         // empty: the preset's
  std::string init, experts, prefix, successors = "scripted", activation, preset;
  bool json = false, quiet = false, show_preset = false;
  std::size_t threads = 0;
};

// The defaults: the preset's spec of the role named on the command line.
Options preset_defaults(int argc, char** argv) {
  const training::Preset& preset = tools::preset_in_args(argc, argv);
  Options o;
  o.preset = std::string(preset.name);
  o.spec = training::preset_spec(preset, tools::value_in_args(argc, argv, "--role", "approach"));
  o.prefix = preset.chained_experts ? "chained" : "scripted";
  o.activation = std::string(nn::activation_name(o.spec.ddpg.hidden_activation));
  return o;
}

void add_ddpg_options(CLI::App& app, Options& o) {
  rl::DdpgHerConfig& d = o.spec.ddpg;
  app.add_option("--hidden", d.hidden, "hidden widths of actor and critic")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--activation", o.activation, "hidden activation: relu, elu or tanh")
      ->capture_default_str();
  app.add_option("--batch-size", d.batch_size)->capture_default_str();
  app.add_option("--buffer-size", d.buffer_size)->capture_default_str();
  app.add_option("--actor-lr", d.actor_learning_rate)->capture_default_str();
  app.add_option("--critic-lr", d.critic_learning_rate)->capture_default_str();
  app.add_option("--gamma", d.gamma)->capture_default_str();
  app.add_option("--polyak", d.polyak)->capture_default_str();
  app.add_option("--polyak-every-updates", d.polyak_every_updates,
                 "targets move by --polyak per this many gradient steps (0: once per cycle)")
      ->capture_default_str();
  app.add_option("--her-k", d.her_k)->capture_default_str();
  app.add_option("--noise-eps", d.noise_eps)->capture_default_str();
  app.add_option("--random-eps", d.random_eps)->capture_default_str();
  app.add_option("--action-l2", d.action_l2)->capture_default_str();
  app.add_option("--gripper-commitment", d.gripper_commitment,
                 "weight of the prior pushing a learned gripper command to an end")
      ->capture_default_str();
  app.add_option("--episodes-per-cycle", d.episodes_per_cycle)->capture_default_str();
  app.add_option("--updates-per-cycle", d.updates_per_cycle)->capture_default_str();
  app.add_option("--updates-per-transition", d.updates_per_transition,
                 "> 0: gradient steps per stored transition instead of --updates-per-cycle")
      ->capture_default_str();
  app.add_option("--gripper-script", o.gripper_script,
                 "when the gripper is scripted: grasp_rule (closed once centred on the object) "
                 "or per_subtask (the paper's code: approach open, then closed) [the preset's]");
  app.add_flag("--scripted-gripper,!--learned-gripper", o.spec.scripted_gripper,
               "keep the gripper command scripted, as the paper's code, or learn it [preset]");
  app.add_option("--demo-episodes", d.demo_episodes,
                 "scripted demonstrations before exploring (counted)")
      ->capture_default_str();
  app.add_option("--demo-pretrain-updates", d.demo_pretrain_updates)->capture_default_str();
  app.add_option("--demo-bc-weight", d.demo_bc_weight, "behaviour-cloning weight on demonstrations")
      ->capture_default_str();
}

void write_outputs(const Options& o, const std::vector<std::uint8_t>& checkpoint,
                   const nlohmann::json& summary) {
  std::filesystem::create_directories(o.out);
  nn::write_file_atomically(o.out + "/" + o.spec.role + ".ckpt", checkpoint);
  const std::string text = summary.dump(2) + "\n";
  nn::write_file_atomically(o.out + "/" + o.spec.role + ".json",
                            {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

std::vector<std::string> split(const std::string& list) {
  std::vector<std::string> items;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');) items.push_back(item);
  return items;
}

// The experts before the trained subtask: --prefix scripted (the paper), chained (the
// checkpoints of the earlier roles in --out) or one comma-separated checkpoint or
// "scripted" each.
std::vector<std::string> prefix_specs(const Options& o) {
  const auto count = static_cast<std::size_t>(sim::parse_subtask(o.spec.role, "--role"));
  if (o.prefix == "scripted" || o.prefix == "chained") {
    std::vector<std::string> specs;
    for (std::size_t k = 0; k < count; ++k) {
      const std::string earlier(sim::subtask_name(sim::kAllSubtasks[k]));
      const std::string path = o.out + "/" + earlier + ".ckpt";
      if (o.prefix == "chained" && !std::filesystem::exists(path)) {
        throw_invalid_argument("--prefix chained",
                               "the " + earlier + " expert trained first (pnp-train --role " +
                                   earlier + " --out " + o.out + "), or --prefix scripted",
                               "no file " + path);
      }
      specs.push_back(o.prefix == "scripted" ? "scripted" : path);
    }
    return specs;
  }
  std::vector<std::string> specs = split(o.prefix);
  if (specs.size() != count) {
    throw_invalid_argument("--prefix",
                           "scripted, chained, or " + std::to_string(count) +
                               " comma-separated checkpoints (or \"scripted\") for the subtasks "
                               "before " +
                               o.spec.role,
                           "\"" + o.prefix + "\"");
  }
  return specs;
}

// The experts after the trained subtask in evaluation: scripted (the paper), or one
// comma-separated checkpoint or "scripted" each.
std::vector<std::string> successor_specs(const Options& o) {
  const auto own = static_cast<std::size_t>(sim::parse_subtask(o.spec.role, "--role"));
  const std::size_t count = sim::kNumSubtasks - own - 1;
  if (o.successors == "scripted") return std::vector<std::string>(count, "scripted");
  std::vector<std::string> specs = split(o.successors);
  if (specs.size() != count) {
    throw_invalid_argument("--successors",
                           "scripted, or " + std::to_string(count) +
                               " comma-separated checkpoints (or \"scripted\") for the subtasks "
                               "after " +
                               o.spec.role,
                           "\"" + o.successors + "\"");
  }
  return specs;
}

// The choreographer's experts: --experts, or the three checkpoints in --out.
std::vector<std::string> expert_specs(const Options& o) {
  std::vector<std::string> specs;
  if (o.experts.empty()) {
    for (auto s : sim::kAllSubtasks)
      specs.push_back(o.out + "/" + std::string(sim::subtask_name(s)) + ".ckpt");
    return specs;
  }
  specs = split(o.experts);
  if (specs.size() != sim::kNumSubtasks) {
    throw_invalid_argument("--experts", "three comma-separated checkpoints (or \"scripted\")",
                           std::to_string(specs.size()) + " items");
  }
  return specs;
}

nlohmann::json train(Options& o) {
  o.spec.robot = sim::parse_robot(o.robot, "--robot");
  o.spec.ddpg.hidden_activation = nn::parse_activation(o.activation, "--activation");
  o.spec.object = sim::parse_object(o.object, "--object");
  o.spec.world = sim::parse_world_profile(o.world, "--world");
  o.spec.actuation = o.actuation == "default" ? sim::default_actuation(o.spec.robot)
                                              : sim::parse_actuation(o.actuation, "--actuation");
  sim::require_supported(o.spec.robot, o.spec.actuation, "--actuation");
  if (!o.gripper_script.empty())
    o.spec.gripper_script = sim::parse_gripper_script(o.gripper_script, "--gripper-script");
  training::TrainingInputs inputs;
  if (!o.init.empty()) inputs.init = nn::read_file(o.init);
  std::vector<std::string> experts;
  if (o.spec.role == "hlc") {
    experts = expert_specs(o);
  } else if (o.spec.is_expert()) {
    experts = prefix_specs(o);
    experts.push_back("scripted");  // the trained subtask's own entry
    for (const std::string& after : successor_specs(o)) experts.push_back(after);
  }
  for (std::size_t k = 0; k < experts.size(); ++k)
    if (experts[k] != "scripted") inputs.experts[k] = nn::read_file(experts[k]);
  training::TrainingHooks hooks;
  hooks.threads = o.threads;
  hooks.progress = [&](const rl::CurvePoint& p) {
    if (!o.quiet) tools::print_progress(stderr, o.spec.role, p);
  };
  const training::TrainingOutcome outcome =
      training::train_role(o.spec, inputs, hooks, kCodeCommit);
  nlohmann::json summary = training::result_json(outcome.result);
  summary["role"] = o.spec.role;
  summary["algo"] = o.spec.algorithm;
  summary["robot"] = o.robot;
  summary["object"] = o.object;
  summary["world"] = o.world;
  summary["actuation"] = sim::actuation_name(o.spec.actuation);
  summary["seed"] = o.spec.seed;
  summary["preset"] = o.preset;
  summary["uses_demonstrations"] = o.spec.ddpg.demo_episodes > 0;
  summary["code_commit"] = kCodeCommit;
  summary["gemm_path"] = nn::gemm_path_name(nn::active_gemm_path());
  summary["config"] = training::to_json(o.spec);
  summary["checkpoint"] = o.out + "/" + o.spec.role + ".ckpt";
  if (!o.init.empty()) summary["init"] = o.init;
  if (o.spec.role == "hlc") summary["experts"] = experts;
  if (o.spec.is_expert()) {
    const auto own = static_cast<std::ptrdiff_t>(sim::parse_subtask(o.spec.role, "--role"));
    summary["prefix"] = std::vector<std::string>(experts.begin(), experts.begin() + own);
    summary["successors"] = std::vector<std::string>(experts.begin() + own + 1, experts.end());
  }
  write_outputs(o, outcome.checkpoint, summary);
  return summary;
}

// What a person reads: the outcome in two lines (--json prints the whole object).
void print_summary(const Options& o, const nlohmann::json& s) {
  const double target = o.spec.stop.target_success;
  const double wall = s.at("wall_s").get<double>() - s.at("eval_wall_s").get<double>();
  if (s.at("reached").get<bool>()) {
    std::printf(
        "%s: reached %.2f twice in a row at %lld training steps (score %.2f), %.1f s of "
        "training\n",
        o.spec.role.c_str(), target, s.at("steps_to_target").get<long long>(),
        s.at("final_score").get<double>(), wall);
  } else {
    std::printf(
        "%s: target %.2f NOT reached: score %.2f at %lld training steps%s, %.1f s of "
        "training\n",
        o.spec.role.c_str(), target, s.at("final_score").get<double>(),
        s.at("train_env_steps").get<long long>(),
        s.at("cancelled").get<bool>() ? " (cancelled)" : " (the step cap)", wall);
  }
  if (s.contains("wall_breakdown")) {
    const auto& b = s.at("wall_breakdown");
    std::printf(
        "  wall time %.1f s: rollouts %.1f, updates %.1f, evaluation %.1f, checkpoints and store "
        "%.1f, other %.1f\n",
        b.at("total_s").get<double>(), b.at("rollout_s").get<double>(),
        b.at("update_s").get<double>(), b.at("eval_s").get<double>(),
        b.at("report_s").get<double>(), b.at("other_s").get<double>());
  }
  std::printf(
      "  preset %s, %s, %s world (%s hand), %s/%s, seed %llu, GEMM path %s; checkpoint %s (the "
      "whole result: %s/%s.json, or --json)\n",
      o.preset.c_str(), o.spec.algorithm.c_str(), o.world.c_str(),
      std::string(sim::actuation_name(o.spec.actuation)).c_str(), o.robot.c_str(), o.object.c_str(),
      static_cast<unsigned long long>(o.spec.seed), s.at("gemm_path").get<std::string>().c_str(),
      s.at("checkpoint").get<std::string>().c_str(), o.out.c_str(), o.spec.role.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Train a subtask expert, the choreographer or a baseline, locally", "pnp-train"};
  Options o = preset_defaults(argc, argv);
  tools::add_preset_options(app, o.preset, o.show_preset);
  app.add_option("--role", o.spec.role, "approach, manipulate, retract, hlc or e2e")
      ->capture_default_str();
  app.add_option("--algo", o.spec.algorithm,
                 "ddpg_her, bc (online, DAgger-style), bc_offline or a3c")
      ->capture_default_str();
  app.add_option("--robot", o.robot)->capture_default_str();
  app.add_option("--object", o.object)->capture_default_str();
  app.add_option("--world", o.world, "world profile: paper or gym (docs/SIMULATION.md)")
      ->capture_default_str();
  app.add_option("--actuation", o.actuation,
                 "how the hand follows actions: mocap (gym's), arm (the Panda's controller) or "
                 "default (the robot's own: docs/SIMULATION.md)")
      ->capture_default_str();
  app.add_option("--seed", o.spec.seed)->check(pnp::seed_value())->capture_default_str();
  app.add_option("--max-steps", o.spec.stop.max_steps, "training environment steps cap")
      ->capture_default_str();
  app.add_option("--target-success", o.spec.stop.target_success,
                 "task success to reach twice in a row")
      ->capture_default_str();
  app.add_option("--eval-interval", o.spec.stop.eval_interval_steps,
                 "training steps between evaluations")
      ->capture_default_str();
  app.add_option("--eval-episodes", o.spec.stop.eval_episodes)->capture_default_str();
  app.add_flag("--fresh-eval-scenes,!--fixed-eval-scenes", o.spec.stop.fresh_eval_scenes,
               "new evaluation scenes at every evaluation (default), or the same ones every time");
  app.add_option("--out", o.out, "output directory for checkpoints")->capture_default_str();
  app.add_option("--init", o.init, "checkpoint to fine-tune from");
  app.add_option("--experts", o.experts, "hlc: approach,manipulate,retract checkpoints");
  app.add_option("--prefix", o.prefix,
                 "experts before this subtask: scripted, chained (earlier checkpoints in --out) "
                 "or comma-separated checkpoints")
      ->capture_default_str();
  app.add_option("--successors", o.successors,
                 "experts after this subtask in evaluation: scripted, or comma-separated "
                 "checkpoints (backward chaining: docs/LEARNING.md)")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "worker threads (0: all cores)");
  app.add_flag("--json", o.json, "print the whole result as one JSON object");
  app.add_flag("--quiet", o.quiet, "no progress lines on stderr");
  add_ddpg_options(app, o);
  app.add_option("--workers", o.spec.a3c.workers,
                 "hlc: A3C workers (the result depends on this, not on threads)")
      ->capture_default_str();
  app.add_option("--hlc-lr", o.spec.a3c.learning_rate)->capture_default_str();
  app.add_option("--entropy", o.spec.a3c.entropy_weight)->capture_default_str();
  app.add_option("--chain-prior", o.spec.a3c.network.chain_prior,
                 "hlc: logit bonus for the next unfinished subtask in the experts' order")
      ->capture_default_str();
  app.add_option("--exploring-starts", o.spec.a3c.exploring_starts,
                 "hlc: fraction of training episodes whose first subtask is drawn uniformly")
      ->capture_default_str();
  app.add_option("--hlc-gamma", o.spec.a3c.gamma, "hlc: discount per environment step")
      ->capture_default_str();
  app.add_flag("--predicate-inputs,!--no-predicate-inputs", o.spec.a3c.network.predicate_inputs,
               "hlc: the three subtask predicates as inputs");
  app.add_flag("--mask-finished,!--no-mask-finished", o.spec.a3c.network.mask_finished,
               "hlc: finished subtasks cannot be chosen");
  return tools::run_tool(app, argc, argv, [&] {
    if (o.show_preset) {
      std::cout << training::to_json(training::find_preset(o.preset, "--preset")).dump(2) << "\n";
      return;
    }
    o.spec.validate();
    nn::active_gemm_path();                             // a bad PNP_GEMM is refused before any work
    tools::require_writable_directory(o.out, "--out");  // and an --out it cannot write
    const nlohmann::json summary = train(o);
    if (o.json) {
      std::cout << summary.dump() << "\n";
    } else {
      print_summary(o, summary);
    }
  });
}
