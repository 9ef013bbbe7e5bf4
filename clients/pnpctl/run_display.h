#pragma once
// How pnpctl shows a training run: its outcome, the stop rule's score beside task success,
// its progress line and its name in a plot's legend. Pure formatting, no calls.

#include <string>
#include <vector>

#include "pnp/train/v1/train_service.pb.h"

namespace pnp::pnpctl {

// The run's state, with a finished run's outcome: "reached" (its target, twice in a row)
// or "not-reached" (it stopped at its step cap) instead of "succeeded"; otherwise the
// state ("running", "failed", ...).
std::string outcome_text(const train::v1::TrainingRun& run);

// The stop rule's score at the last evaluation, "0.70"; "-" for a run stored before the
// score was kept.
std::string score_text(const train::v1::TrainingRun& run);

// Where the run's wall time went, as `pnpctl runs` shows it: its total ("1m05s") and the
// shares of rollouts, updates and evaluation ("12%"); "-" each while no trainer's part has
// ended (the store sums a run's parts as they end).
std::vector<std::string> wall_columns(const train::v1::TrainingRun& run);
inline const std::vector<std::string> kWallColumnNames = {"wall", "rollout", "updates", "eval"};

// "approach  run 3  [#######-------]  12.0k/60.0k steps  score 0.70/0.97  success 0.84
//  eta<=0m41s  running"
std::string progress_line(const train::v1::TrainingRun& run, const train::v1::MetricPoint* metric,
                          int width);

// A learning curve's legend entry: "approach ddpg_her seed 1 (run 3)".
std::string series_label(const train::v1::TrainingRun& run);

// Runs gathered from several training services, newest (highest id) first, as `pnpctl
// runs` lists them whatever order the services answered in.
void order_newest_first(std::vector<train::v1::TrainingRun>& runs);

}  // namespace pnp::pnpctl
