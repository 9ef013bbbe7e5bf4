#include "clients/pnpctl/run_display.h"

#include <algorithm>
#include <cmath>

#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/table.h"
#include "store/records.h"

namespace pnp::pnpctl {
namespace {

std::string steps_text(long long steps) {
  return fixed(static_cast<double>(steps) / 1000, 1) + "k";
}

}  // namespace

std::string outcome_text(const train::v1::TrainingRun& run) {
  return std::string(
      store::run_outcome(store::parse_run_state(short_name(run.state())), run.reached()));
}

std::string score_text(const train::v1::TrainingRun& run) {
  return run.has_last_score() ? fixed(run.last_score(), 2) : "-";
}

std::vector<std::string> wall_columns(const train::v1::TrainingRun& run) {
  const auto& wall = run.wall_breakdown();
  if (!(wall.total_s() > 0)) return std::vector<std::string>(kWallColumnNames.size(), "-");
  const auto share = [&](double seconds) {
    return std::to_string(static_cast<int>(std::lround(100 * seconds / wall.total_s()))) + "%";
  };
  return {duration_text(wall.total_s()), share(wall.rollout_s()), share(wall.update_s()),
          share(wall.eval_s())};
}

std::string progress_line(const train::v1::TrainingRun& run, const train::v1::MetricPoint* metric,
                          int width) {
  const double fraction =
      run.max_steps() > 0
          ? std::clamp(static_cast<double>(run.env_steps()) / static_cast<double>(run.max_steps()),
                       0.0, 1.0)
          : 0.0;
  const int filled = static_cast<int>(fraction * width);
  std::string line = short_name(run.role()) + "  run " + std::to_string(run.run_id()) + "  [" +
                     std::string(static_cast<std::size_t>(filled), '#') +
                     std::string(static_cast<std::size_t>(width - filled), '-') + "]  " +
                     steps_text(run.env_steps()) + "/" + steps_text(run.max_steps()) + " steps";
  // The score is what decides when the run stops; task success is what a user wants.
  const bool has_score = metric ? metric->has_stop_score() : run.has_last_score();
  if (has_score) {
    line += "  score " + fixed(metric ? metric->stop_score() : run.last_score(), 2) + "/" +
            fixed(run.target_success(), 2);
  }
  line += "  success " + fixed(metric ? metric->task_success() : run.last_success(), 2);
  if (metric && metric->sampled_success() > 0)
    line += "  sampled " + fixed(metric->sampled_success(), 2);
  if (run.has_eta()) line += "  eta<=" + duration_text(static_cast<double>(run.eta().seconds()));
  line += "  " + outcome_text(run);
  return line;
}

std::string series_label(const train::v1::TrainingRun& run) {
  return short_name(run.role()) + " " + short_name(run.algorithm()) + " seed " +
         std::to_string(run.seed()) + " (run " + std::to_string(run.run_id()) + ")";
}

void order_newest_first(std::vector<train::v1::TrainingRun>& runs) {
  std::stable_sort(runs.begin(), runs.end(),
                   [](const auto& a, const auto& b) { return a.run_id() > b.run_id(); });
}

}  // namespace pnp::pnpctl
