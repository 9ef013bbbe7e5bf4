#pragma once
// One cell of Table I: every method of the table under one preset in one world, over
// several seeds, with RESULTS.md, the curves CSV and the SVG rewritten under the output
// directory after every finished run, so a long run's results are never lost.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/paper_table/experiments.h"
#include "tools/paper_table/report.h"
#include "training/preset.h"

namespace pnp::tools {

struct TablePlan {
  ExperimentSettings settings;     // DDPG+HER, BC with our networks, end-to-end
  ExperimentSettings bc_original;  // BC with the original code's networks and schedule
  int seeds = 5;                   // DDPG+HER hierarchies
  int baseline_seeds = 3;          // BC (both) and end-to-end
  std::uint64_t first_seed = 0;
  bool skip_ddpg_her = false;  // no DDPG+HER rows on fetch (the Panda row: skip_panda)
  bool skip_bc = false, skip_bc_original = false, skip_e2e = false, skip_panda = false;
};

// The settings a preset names, in `world`: every value from the preset.
ExperimentSettings preset_settings(const training::Preset& preset, sim::WorldProfile world);
// The original code's BC (2 x 128 ELU, lr 1e-4, one update per step) beside `s`.
ExperimentSettings bc_original_settings(const ExperimentSettings& s, int eval_interval_steps);

struct TableResult {
  std::vector<MethodRun> runs;     // on the plan's robot (fetch)
  std::optional<MethodRun> panda;  // the DDPG+HER hierarchy on the Panda, first seed
  std::string markdown;            // RESULTS.md as last written
};

// Runs the plan; `context` supplies how the report is headed (command, commit, preset...);
// its seeds and held-out rows are filled in here.
TableResult run_table(const TablePlan& plan, ReportContext context,
                      const std::filesystem::path& out, const Progress& progress);

}  // namespace pnp::tools
