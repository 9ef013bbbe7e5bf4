// pnp-paper-table: reproduces the paper's Table I (DDPG+HER experts + HLC, BC experts +
// HLC with our networks and with the original code's, end-to-end DDPG+HER; several seeds;
// all to the same success level) in one world profile under one training preset
// (training/preset.h), evaluates the final hierarchies on 1000 held-out episodes on both
// robots, and writes OUT/RESULTS.md, OUT/results/curves.csv and
// OUT/results/learning_curves.svg (OUT: runs/paper-table). --grid runs every world x
// every preset, one such directory per cell, and a summary page.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "build_info.h"
#include "common/error.h"
#include "common/seed_flag.h"
#include "common/validate.h"
#include "nn/gemm_path.h"
#include "tools/common/cli.h"
#include "tools/common/preset_option.h"
#include "tools/common/progress_line.h"
#include "tools/paper_table/report.h"
#include "tools/paper_table/table_run.h"

namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// Options that change one value of a preset: the grid runs every preset as it is named.
// A flag and its negation count as one option; the error names both.
struct Override {
  const char* option;
  const char* spelled;
};
constexpr Override kSingleValueOverrides[] = {
    {"--prefix", "--prefix"},
    {"--updates-per-transition", "--updates-per-transition"},
    {"--expert-target", "--expert-target"},
    {"--hlc-target", "--hlc-target"},
    {"--hlc-gamma", "--hlc-gamma"},
    {"--hlc-entropy", "--hlc-entropy"},
    {"--hlc-exploring-starts", "--hlc-exploring-starts"},
    {"--chain-prior", "--chain-prior"},
    {"--learned-gripper", "--learned-gripper or --scripted-gripper"},
    {"--predicate-inputs", "--predicate-inputs or --no-predicate-inputs"},
    {"--mask-finished", "--mask-finished or --no-mask-finished"},
    {"--fresh-eval-scenes", "--fresh-eval-scenes or --fixed-eval-scenes"},
    {"--world", "--world"},
    {"--preset", "--preset"}};

}  // namespace

int main(int argc, char** argv) {
  using namespace pnp;
  CLI::App app{"Reproduce the paper's Table I and write RESULTS.md", "pnp-paper-table"};
  const training::Preset& preset = tools::preset_in_args(argc, argv);
  std::string preset_name(preset.name);
  bool show_preset = false;
  tools::add_preset_options(app, preset_name, show_preset);
  std::string world(sim::world_profile_name(sim::kDefaultWorldProfile));
  app.add_option("--world", world, "world profile: paper or gym (docs/SIMULATION.md)")
      ->capture_default_str();
  bool grid = false;
  app.add_flag("--grid", grid,
               "the whole matrix: every world x every preset, each cell in OUT/WORLD-PRESET/ "
               "and a summary in OUT/RESULTS.md (days on 2 cores; takes no per-value overrides)");
  tools::TablePlan plan;
  bool quick = false;
  long long e2e_max_steps = preset.e2e_stop.max_steps,
            expert_max_steps = preset.expert_stop.max_steps,
            hlc_max_steps = preset.hlc_stop.max_steps;
  std::string out_dir = "runs/paper-table",
              prefix = preset.chained_experts ? "chained" : "scripted";
  tools::ExperimentSettings s = tools::preset_settings(preset, sim::kDefaultWorldProfile);
  app.add_option("--seeds", plan.seeds, "seeds of the DDPG+HER hierarchy")->capture_default_str();
  app.add_option("--baseline-seeds", plan.baseline_seeds,
                 "seeds of each baseline (BC, BC with the original networks, end-to-end)")
      ->capture_default_str();
  app.add_option("--first-seed", plan.first_seed)->check(pnp::seed_value())->capture_default_str();
  app.add_flag("--quick", quick,
               "one seed; caps: experts 15k, HLC 20k, end-to-end 40k steps; 500 held-out episodes");
  app.add_option("--e2e-max-steps", e2e_max_steps,
                 "end-to-end cap (316k: the paper's hierarchy total, enough to settle the "
                 "ordering)")
      ->capture_default_str();
  app.add_option("--expert-max-steps", expert_max_steps)->capture_default_str();
  app.add_option("--hlc-max-steps", hlc_max_steps)->capture_default_str();
  app.add_flag("--skip-ddpg-her", plan.skip_ddpg_her,
               "skip the DDPG+HER hierarchies on fetch (the Panda row has --skip-panda)");
  app.add_flag("--skip-bc", plan.skip_bc);
  app.add_flag("--skip-bc-original", plan.skip_bc_original,
               "skip BC with the original code's networks and schedule (2 x 128 ELU, lr 1e-4, "
               "one update per step)");
  int bc_original_eval_interval = 5000;
  app.add_option("--bc-original-eval-interval", bc_original_eval_interval,
                 "training steps between evaluations of original-BC experts (they need many)")
      ->capture_default_str();
  app.add_flag("--skip-e2e", plan.skip_e2e);
  app.add_flag("--skip-panda", plan.skip_panda,
               "skip the held-out evaluation of a hierarchy trained on panda");
  app.add_option("--prefix", prefix,
                 "experts before each trained expert: chained (the learned ones) or scripted "
                 "(the paper)")
      ->capture_default_str();
  app.add_option("--updates-per-transition", s.ddpg.updates_per_transition,
                 "DDPG+HER and BC gradient steps per stored transition (0: the original's 40 "
                 "per cycle)")
      ->capture_default_str();
  app.add_flag("--learned-gripper,!--scripted-gripper", s.ddpg.learn_gripper,
               "experts learn the gripper command, or keep it scripted as the paper [preset]");
  app.add_option("--gripper-commitment", s.ddpg.gripper_commitment,
                 "weight of the prior pushing a learned gripper command to an end [preset]")
      ->capture_default_str();
  double expert_target = preset.expert_stop.target_success;
  app.add_option("--expert-target", expert_target,
                 "task success each subtask expert must reach (twice in a row)")
      ->capture_default_str();
  double hlc_target = preset.hlc_stop.target_success;
  app.add_option("--hlc-target", hlc_target,
                 "task success the choreographer must reach (twice in a row)")
      ->capture_default_str();
  bool fresh_eval_scenes = true;
  app.add_flag("--fresh-eval-scenes,!--fixed-eval-scenes", fresh_eval_scenes,
               "new evaluation scenes at every evaluation (default), or the same ones every time");
  app.add_option("--hlc-gamma", s.a3c.gamma, "the choreographer's discount per environment step")
      ->capture_default_str();
  app.add_option("--hlc-entropy", s.a3c.entropy_weight,
                 "weight of the choreographer's entropy bonus")
      ->capture_default_str();
  app.add_option("--chain-prior", s.a3c.network.chain_prior,
                 "logit bonus for the subtask after the furthest finished one, in the experts' "
                 "order [preset]")
      ->capture_default_str();
  app.add_option("--hlc-exploring-starts", s.a3c.exploring_starts,
                 "fraction of the choreographer's training episodes whose first subtask is "
                 "drawn uniformly")
      ->capture_default_str();
  app.add_flag("--predicate-inputs,!--no-predicate-inputs", s.a3c.network.predicate_inputs,
               "the choreographer sees the three subtask predicates [preset]");
  app.add_flag("--mask-finished,!--no-mask-finished", s.a3c.network.mask_finished,
               "finished subtasks cannot be chosen by the choreographer [preset]");
  std::size_t threads = 0;
  app.add_option("--threads", threads, "worker threads (0: all cores)");
  app.add_option("--out", out_dir,
                 "where RESULTS.md and results/ go (docs: replace the committed results)")
      ->capture_default_str();
  return tools::run_tool(app, argc, argv, [&] {
    if (show_preset) {
      std::printf("%s\n", training::to_json(preset).dump(2).c_str());
      return;
    }
    require_positive(plan.seeds, "--seeds");
    require_positive(plan.baseline_seeds, "--baseline-seeds");
    require_positive(bc_original_eval_interval, "--bc-original-eval-interval");
    if (prefix != "chained" && prefix != "scripted")
      throw_invalid_argument("--prefix", "chained or scripted", "\"" + prefix + "\"");
    if (!(expert_target > 0 && expert_target <= 1))
      throw_invalid_argument("--expert-target", "a value in (0, 1]", std::to_string(expert_target));
    if (!(hlc_target > 0 && hlc_target <= 1))
      throw_invalid_argument("--hlc-target", "a value in (0, 1]", std::to_string(hlc_target));
    if (grid) {
      for (const Override& o : kSingleValueOverrides) {
        if (app.count(o.option) > 0)
          throw_invalid_argument("--grid", "no per-value overrides (each cell runs its preset)",
                                 o.spelled);
      }
    }
    if (quick) {
      plan.seeds = plan.baseline_seeds = 1;
      s.held_out_episodes = 500;
    }
    // The caps: typed ones apply to every cell; otherwise each preset's own (or --quick's).
    auto apply_caps = [&](tools::ExperimentSettings& cell, const training::Preset& p) {
      cell.threads = threads;
      cell.held_out_episodes = s.held_out_episodes;
      auto cap = [&](const char* option, long long typed, long long own, long long quick_cap) {
        if (app.count(option) > 0) return typed;
        return quick ? std::min(own, quick_cap) : own;
      };
      cell.e2e_stop.max_steps = cap("--e2e-max-steps", e2e_max_steps, p.e2e_stop.max_steps, 40'000);
      cell.expert_stop.max_steps =
          cap("--expert-max-steps", expert_max_steps, p.expert_stop.max_steps, 15'000);
      cell.hlc_stop.max_steps = cap("--hlc-max-steps", hlc_max_steps, p.hlc_stop.max_steps, 20'000);
    };
    // "ddpg_her seed 2/approach  ...": which of the table's runs each line is.
    auto progress = [](const std::string& method, std::uint64_t seed, const std::string& role,
                       const rl::CurvePoint& p) {
      tools::print_progress(stderr, method + " seed " + std::to_string(seed) + "/" + role, p);
    };
    tools::ReportContext context;
    context.command = "build/bin/pnp-paper-table";
    for (int i = 1; i < argc; ++i) context.command += std::string(" ") + argv[i];
    context.code_commit = kCodeCommit;
    context.gemm_path = nn::gemm_path_name(nn::active_gemm_path());  // refuses a bad PNP_GEMM
    context.quick = quick;
    tools::require_writable_directory(out_dir, "--out");  // before hours of training
    const std::filesystem::path out(out_dir);

    if (!grid) {
      s.world = sim::parse_world_profile(world, "--world");
      s.chained = prefix == "chained";
      s.expert_stop.target_success = expert_target;
      s.hlc_stop.target_success = hlc_target;
      for (rl::StopRule* rule : {&s.expert_stop, &s.hlc_stop, &s.e2e_stop})
        rule->fresh_eval_scenes = fresh_eval_scenes;
      apply_caps(s, preset);
      s.ddpg.validate();
      s.a3c.validate();
      plan.settings = s;
      plan.bc_original = tools::bc_original_settings(s, bc_original_eval_interval);
      context.preset = preset_name;
      context.uses_demonstrations = preset.uses_demonstrations;
      const tools::TableResult result = tools::run_table(plan, context, out, progress);
      std::printf("%s", result.markdown.c_str());
      return;
    }
    std::vector<tools::GridCell> cells;
    for (const sim::WorldProfile cell_world : sim::kAllWorldProfiles) {
      for (const training::Preset& p : training::presets()) {
        tools::GridCell cell{std::string(sim::world_profile_name(cell_world)),
                             std::string(p.name),
                             p.uses_demonstrations,
                             {},
                             {},
                             {},
                             0.0};
        cell.results_path = cell.world + "-" + cell.preset + "/RESULTS.md";
        tools::ExperimentSettings cell_settings = tools::preset_settings(p, cell_world);
        apply_caps(cell_settings, p);
        plan.settings = cell_settings;
        plan.bc_original = tools::bc_original_settings(cell_settings, bc_original_eval_interval);
        tools::ReportContext cell_context = context;
        cell_context.preset = cell.preset;
        cell_context.uses_demonstrations = p.uses_demonstrations;
        const auto cell_start = std::chrono::steady_clock::now();
        tools::TableResult result =
            tools::run_table(plan, cell_context, out / (cell.world + "-" + cell.preset), progress);
        cell.runs = std::move(result.runs);
        cell.panda = std::move(result.panda);
        cell.wall_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - cell_start).count();
        std::fprintf(stderr, "cell %s/%s: %.1f s\n", cell.world.c_str(), cell.preset.c_str(),
                     cell.wall_s);
        cells.push_back(std::move(cell));
        context.settings = cell_settings;
        write_text(out / "RESULTS.md", tools::grid_markdown(cells, context));
      }
    }
    std::printf("%s", tools::grid_markdown(cells, context).c_str());
  });
}
