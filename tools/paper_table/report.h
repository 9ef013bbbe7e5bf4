#pragma once
// Writes the results of the Table I experiments: docs/RESULTS.md (tables with the paper's
// numbers beside ours), a CSV of every learning curve, and an SVG of the curves.

#include <optional>
#include <string>
#include <vector>

#include "tools/paper_table/experiments.h"

namespace pnp::tools {

struct ReportContext {
  std::string command;  // how to reproduce
  std::string code_commit;
  std::string gemm_path;  // nn/gemm_path.h
  std::vector<std::uint64_t> seeds;
  bool quick = false;
  std::string preset;  // training/preset.h
  bool uses_demonstrations = false;
  ExperimentSettings settings;
  int bc_original_eval_interval = 0;  // training steps between its evaluations
  std::vector<std::pair<std::string, double>>
      held_out;  // "robot object" -> success (1000 episodes)
};

std::string results_markdown(const std::vector<MethodRun>& runs, const ReportContext& context);

// One cell of the --grid matrix: a world and a preset, its runs on fetch and the Panda's.
struct GridCell {
  std::string world, preset;
  bool uses_demonstrations = false;
  std::string results_path;  // the cell's RESULTS.md, relative to the grid's
  std::vector<MethodRun> runs;
  std::optional<MethodRun> panda;
  double wall_s = 0;  // the whole cell: training, evaluation, held-out episodes, reports
};
// The cell's trainers' wall time by phase, summed over its runs and their parts.
WallBreakdown training_phases(const GridCell& cell);
// The matrix on one page: per cell, each method's total steps (mean ± sd, k/n reached),
// the DDPG+HER hierarchies' held-out success, and the cell's wall time with its trainers'
// evaluation share; then the whole grid's time.
std::string grid_markdown(const std::vector<GridCell>& cells, const ReportContext& context);
std::string curves_csv(const std::vector<MethodRun>& runs);
std::string curves_svg(const std::vector<MethodRun>& runs);

}  // namespace pnp::tools
