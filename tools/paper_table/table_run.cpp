#include "tools/paper_table/table_run.h"

#include <fstream>
#include <string>

#include "rl/subtask_trainer.h"

namespace pnp::tools {
namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

std::string held_out_label(const ExperimentSettings& s, sim::Robot robot, std::uint64_t seed) {
  return std::string(sim::world_profile_name(s.world)) + " world, " +
         std::string(sim::robot_name(robot)) + " " + std::string(sim::object_name(s.object)) +
         " (" + std::string(sim::actuation_name(sim::default_actuation(robot))) + " hand), seed " +
         std::to_string(seed);
}

}  // namespace

ExperimentSettings preset_settings(const training::Preset& preset, sim::WorldProfile world) {
  ExperimentSettings s;
  s.world = world;
  s.ddpg = preset.ddpg;
  s.ddpg.learn_gripper = !preset.scripted_gripper;
  s.ddpg.gripper_script = preset.gripper_script;
  s.a3c = preset.a3c;
  s.chained = preset.chained_experts;
  s.expert_stop = preset.expert_stop;
  s.hlc_stop = preset.hlc_stop;
  s.e2e_stop = preset.e2e_stop;
  return s;
}

ExperimentSettings bc_original_settings(const ExperimentSettings& s, int eval_interval_steps) {
  ExperimentSettings out = s;
  out.ddpg = rl::original_bc_config(s.ddpg);
  out.expert_stop.eval_interval_steps = eval_interval_steps;
  return out;
}

TableResult run_table(const TablePlan& plan, ReportContext context,
                      const std::filesystem::path& out, const Progress& progress) {
  const ExperimentSettings& s = plan.settings;
  context.settings = s;
  context.bc_original_eval_interval =
      static_cast<int>(plan.bc_original.expert_stop.eval_interval_steps);
  TableResult result;
  std::vector<MethodRun>& runs = result.runs;
  auto write_all = [&] {
    context.held_out.clear();
    for (const auto& r : runs) {
      if (r.method == "ddpg_her" && r.held_out_success >= 0)
        context.held_out.emplace_back(held_out_label(s, s.robot, r.seed), r.held_out_success);
    }
    if (result.panda) {
      context.held_out.emplace_back(held_out_label(s, sim::Robot::kPanda, result.panda->seed),
                                    result.panda->held_out_success);
    }
    result.markdown = results_markdown(runs, context);
    write_text(out / "RESULTS.md", result.markdown);
    write_text(out / "results" / "curves.csv", curves_csv(runs));
    write_text(out / "results" / "learning_curves.svg", curves_svg(runs));
  };
  const int rounds =
      plan.skip_ddpg_her ? plan.baseline_seeds : std::max(plan.seeds, plan.baseline_seeds);
  for (int k = 0; k < rounds; ++k) {
    const std::uint64_t seed = plan.first_seed + static_cast<std::uint64_t>(k);
    context.seeds.push_back(seed);
    if (!plan.skip_ddpg_her && k < plan.seeds) {
      runs.push_back(run_hierarchy("ddpg_her", rl::ExpertAlgorithm::kDdpgHer, seed, s, progress));
      write_all();
    }
    if (k >= plan.baseline_seeds) continue;
    if (!plan.skip_e2e) {
      runs.push_back(run_end_to_end(seed, s, progress));
      write_all();
    }
    if (!plan.skip_bc) {
      runs.push_back(run_hierarchy("bc", rl::ExpertAlgorithm::kBcOnline, seed, s, progress));
      write_all();
    }
    if (!plan.skip_bc_original) {
      runs.push_back(run_hierarchy("bc_original", rl::ExpertAlgorithm::kBcOnline, seed,
                                   plan.bc_original, progress));
      write_all();
    }
  }
  if (!plan.skip_panda) {
    ExperimentSettings panda = s;
    panda.robot = sim::Robot::kPanda;
    result.panda =
        run_hierarchy("ddpg_her", rl::ExpertAlgorithm::kDdpgHer, plan.first_seed, panda, progress);
    write_all();
  }
  return result;
}

}  // namespace pnp::tools
