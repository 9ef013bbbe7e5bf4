// pnp-paper-table: reproduces the paper's Table I on the fetch world (DDPG+HER experts +
// HLC, BC experts + HLC, end-to-end DDPG+HER; several seeds; all to the same success
// level) under one training preset (training/preset.h), evaluates the final hierarchy on
// 1000 held-out episodes on both robots, and writes OUT/RESULTS.md, OUT/results/curves.csv
// and OUT/results/learning_curves.svg (OUT: runs/paper-table; --out docs replaces the
// committed results).

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "build_info.h"
#include "common/error.h"
#include "common/validate.h"
#include "nn/gemm_path.h"
#include "tools/common/cli.h"
#include "tools/common/preset_option.h"
#include "tools/common/progress_line.h"
#include "tools/paper_table/report.h"

namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pnp;
  CLI::App app{"Reproduce the paper's Table I and write RESULTS.md", "pnp-paper-table"};
  const training::Preset& preset = tools::preset_in_args(argc, argv);
  std::string preset_name(preset.name);
  bool show_preset = false;
  tools::add_preset_options(app, preset_name, show_preset);
  int seeds = 3;
  std::uint64_t first_seed = 0;
  bool quick = false, skip_bc = false, skip_bc_original = false, skip_e2e = false,
       skip_panda = false;
  long long e2e_max_steps = preset.e2e_stop.max_steps,
            expert_max_steps = preset.expert_stop.max_steps,
            hlc_max_steps = preset.hlc_stop.max_steps;
  std::string out_dir = "runs/paper-table",
              prefix = preset.chained_experts ? "chained" : "scripted";
  tools::ExperimentSettings s;
  s.ddpg = preset.ddpg;
  s.ddpg.learn_gripper = !preset.scripted_gripper;
  s.a3c = preset.a3c;
  std::string world(pnp::sim::world_profile_name(pnp::sim::kDefaultWorldProfile));
  app.add_option("--world", world, "world profile: paper or gym (docs/SIMULATION.md)")
      ->capture_default_str();
  app.add_option("--seeds", seeds, "seeds per method")->capture_default_str();
  app.add_option("--first-seed", first_seed)->capture_default_str();
  app.add_flag("--quick", quick,
               "one seed; caps: experts 15k, HLC 20k, end-to-end 40k steps; 500 held-out episodes");
  app.add_option("--e2e-max-steps", e2e_max_steps)->capture_default_str();
  app.add_option("--expert-max-steps", expert_max_steps)->capture_default_str();
  app.add_option("--hlc-max-steps", hlc_max_steps)->capture_default_str();
  app.add_flag("--skip-bc", skip_bc);
  app.add_flag("--skip-bc-original", skip_bc_original,
               "skip BC with the original code's networks and schedule (2 x 128 ELU, lr 1e-4, "
               "one update per step)");
  int bc_original_eval_interval = 5000;
  app.add_option("--bc-original-eval-interval", bc_original_eval_interval,
                 "training steps between evaluations of original-BC experts (they need many)")
      ->capture_default_str();
  app.add_flag("--skip-e2e", skip_e2e);
  app.add_flag("--skip-panda", skip_panda,
               "skip the held-out evaluation of a hierarchy trained on panda");
  app.add_option("--prefix", prefix,
                 "experts before each trained expert: chained (the learned ones) or scripted "
                 "(the paper)")
      ->capture_default_str();
  app.add_option("--updates-per-transition", s.ddpg.updates_per_transition,
                 "DDPG+HER and BC gradient steps per stored transition (0: the original's 40 "
                 "per cycle)")
      ->capture_default_str();
  double expert_target = preset.expert_stop.target_success;
  app.add_option("--expert-target", expert_target,
                 "task success each subtask expert must reach (twice in a row)")
      ->capture_default_str();
  bool fresh_eval_scenes = true;
  app.add_flag("--fresh-eval-scenes,!--fixed-eval-scenes", fresh_eval_scenes,
               "new evaluation scenes at every evaluation (default), or the same ones every time");
  app.add_option("--hlc-gamma", s.a3c.gamma, "the choreographer's discount per environment step")
      ->capture_default_str();
  app.add_flag("--predicate-inputs,!--no-predicate-inputs", s.a3c.network.predicate_inputs,
               "the choreographer sees the three subtask predicates [preset]");
  app.add_flag("--mask-finished,!--no-mask-finished", s.a3c.network.mask_finished,
               "finished subtasks cannot be chosen by the choreographer [preset]");
  app.add_option("--threads", s.threads, "worker threads (0: all cores)");
  app.add_option("--out", out_dir,
                 "where RESULTS.md and results/ go (docs: replace the committed results)")
      ->capture_default_str();
  return tools::run_tool(app, argc, argv, [&] {
    if (show_preset) {
      std::printf("%s\n", training::to_json(preset).dump(2).c_str());
      return;
    }
    require_positive(seeds, "--seeds");
    s.world = sim::parse_world_profile(world, "--world");
    if (prefix != "chained" && prefix != "scripted")
      throw_invalid_argument("--prefix", "chained or scripted", "\"" + prefix + "\"");
    s.chained = prefix == "chained";
    if (!(expert_target > 0 && expert_target <= 1))
      throw_invalid_argument("--expert-target", "a value in (0, 1]", std::to_string(expert_target));
    if (quick) {
      seeds = 1;
      e2e_max_steps = std::min(e2e_max_steps, 40'000LL);
      expert_max_steps = std::min(expert_max_steps, 15'000LL);
      hlc_max_steps = std::min(hlc_max_steps, 20'000LL);
      s.held_out_episodes = 500;
    }
    s.ddpg.validate();
    s.a3c.validate();
    s.expert_stop = preset.expert_stop;
    s.hlc_stop = preset.hlc_stop;
    s.e2e_stop = preset.e2e_stop;
    s.expert_stop.max_steps = expert_max_steps;
    s.expert_stop.target_success = expert_target;
    s.hlc_stop.max_steps = hlc_max_steps;
    s.e2e_stop.max_steps = e2e_max_steps;
    for (rl::StopRule* rule : {&s.expert_stop, &s.hlc_stop, &s.e2e_stop})
      rule->fresh_eval_scenes = fresh_eval_scenes;
    require_positive(bc_original_eval_interval, "--bc-original-eval-interval");
    tools::ExperimentSettings bc_original = s;
    bc_original.ddpg = rl::original_bc_config(s.ddpg);
    bc_original.expert_stop.eval_interval_steps = bc_original_eval_interval;
    auto progress = [](const std::string& method, const std::string& role,
                       const rl::CurvePoint& p) {
      tools::print_progress(stderr, method + "/" + role, p);
    };
    std::vector<tools::MethodRun> runs;
    tools::ReportContext context;
    context.command = "build/bin/pnp-paper-table";
    for (int i = 1; i < argc; ++i) context.command += std::string(" ") + argv[i];
    context.code_commit = kCodeCommit;
    context.gemm_path = nn::gemm_path_name(nn::active_gemm_path());  // refuses a bad PNP_GEMM
    context.quick = quick;
    context.preset = preset_name;
    context.uses_demonstrations = preset.uses_demonstrations;
    context.settings = s;
    context.bc_original_eval_interval = bc_original_eval_interval;
    const std::filesystem::path out(out_dir);
    // Rewritten after every finished run, so a long run's results are never lost.
    auto write_all = [&] {
      context.held_out.clear();
      for (const auto& r : runs) {
        if (r.method == "ddpg_her" && r.held_out_success >= 0) {
          context.held_out.emplace_back(std::string(sim::world_profile_name(s.world)) + " world, " +
                                            std::string(sim::robot_name(s.robot)) +
                                            " block, seed " + std::to_string(r.seed),
                                        r.held_out_success);
        }
      }
      write_text(out / "RESULTS.md", tools::results_markdown(runs, context));
      write_text(out / "results" / "curves.csv", tools::curves_csv(runs));
      write_text(out / "results" / "learning_curves.svg", tools::curves_svg(runs));
    };
    for (int k = 0; k < seeds; ++k) {
      const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(k);
      context.seeds.push_back(seed);
      runs.push_back(
          tools::run_hierarchy("ddpg_her", rl::ExpertAlgorithm::kDdpgHer, seed, s, progress));
      write_all();
      if (!skip_e2e) {
        runs.push_back(tools::run_end_to_end(seed, s, progress));
        write_all();
      }
      if (!skip_bc) {
        runs.push_back(
            tools::run_hierarchy("bc", rl::ExpertAlgorithm::kBcOnline, seed, s, progress));
        write_all();
      }
      if (!skip_bc_original) {
        runs.push_back(tools::run_hierarchy("bc_original", rl::ExpertAlgorithm::kBcOnline, seed,
                                            bc_original, progress));
        write_all();
      }
    }
    if (!skip_panda) {
      tools::ExperimentSettings panda = s;
      panda.robot = sim::Robot::kPanda;
      const auto r = tools::run_hierarchy("ddpg_her", rl::ExpertAlgorithm::kDdpgHer, first_seed,
                                          panda, progress);
      write_all();
      context.held_out.emplace_back(std::string(sim::world_profile_name(s.world)) +
                                        " world, panda block, seed " + std::to_string(first_seed),
                                    r.held_out_success);
      write_text(out / "RESULTS.md", tools::results_markdown(runs, context));
    }
    std::printf("%s", tools::results_markdown(runs, context).c_str());
  });
}
