// How pnpctl shows a run: a run that stopped at its cap says so, the stop rule's score
// is shown beside task success, and a curve's legend names role, algorithm and seed.
#include <gtest/gtest.h>

#include "clients/pnpctl/run_display.h"

namespace pnp::pnpctl {
namespace {

train::v1::TrainingRun finished_run(bool reached) {
  train::v1::TrainingRun run;
  run.set_run_id(3);
  run.set_role(common::v1::ROLE_APPROACH);
  run.set_algorithm(train::v1::ALGORITHM_DDPG_HER);
  run.set_seed(1);
  run.set_state(train::v1::RUN_STATE_SUCCEEDED);
  run.set_env_steps(20000);
  run.set_max_steps(20000);
  run.set_last_success(1.0);
  run.set_last_score(0.7);
  run.set_target_success(0.97);
  run.set_reached(reached);
  return run;
}

TEST(PnpctlDisplay, AFinishedRunSaysWhetherItReachedItsTarget) {
  EXPECT_EQ(outcome_text(finished_run(true)), "reached");
  EXPECT_EQ(outcome_text(finished_run(false)), "not-reached");
  auto running = finished_run(false);
  running.set_state(train::v1::RUN_STATE_RUNNING);
  EXPECT_EQ(outcome_text(running), "running");
  auto failed = finished_run(false);
  failed.set_state(train::v1::RUN_STATE_FAILED);
  EXPECT_EQ(outcome_text(failed), "failed");
}

TEST(PnpctlDisplay, TheProgressLineShowsTheScoreTheStopRuleUses) {
  const std::string line = progress_line(finished_run(false), nullptr, 10);
  EXPECT_EQ(line,
            "approach  run 3  [##########]  20.0k/20.0k steps  score 0.70/0.97  success 1.00  "
            "not-reached");
  train::v1::MetricPoint point;
  point.set_task_success(0.5);
  point.set_stop_score(0.25);
  EXPECT_NE(progress_line(finished_run(false), &point, 10).find("score 0.25/0.97  success 0.50"),
            std::string::npos);
}

TEST(PnpctlDisplay, ARunStoredBeforeTheScoreWasKeptShowsNoScore) {
  auto old = finished_run(true);
  old.clear_last_score();
  EXPECT_EQ(score_text(old), "-");
  EXPECT_EQ(progress_line(old, nullptr, 4).find("score"), std::string::npos);
  EXPECT_EQ(score_text(finished_run(true)), "0.70");
}

TEST(PnpctlDisplay, TheWallColumnsShowTheTotalAndEachMainPhasesShare) {
  auto run = finished_run(true);
  EXPECT_EQ(wall_columns(run), (std::vector<std::string>{"-", "-", "-", "-"}))
      << "no part of the run has ended";
  auto& wall = *run.mutable_wall_breakdown();
  wall.set_rollout_s(6.5);
  wall.set_update_s(29.0);
  wall.set_eval_s(27.0);
  wall.set_report_s(1.0);
  wall.set_other_s(1.5);
  wall.set_total_s(65.0);
  EXPECT_EQ(wall_columns(run), (std::vector<std::string>{"1m05s", "10%", "45%", "42%"}));
  EXPECT_EQ(wall_columns(run).size(), kWallColumnNames.size());
}

TEST(PnpctlDisplay, ALegendEntryNamesRoleAlgorithmSeedAndRun) {
  EXPECT_EQ(series_label(finished_run(true)), "approach ddpg_her seed 1 (run 3)");
}

// `pnpctl runs` gathers each role's runs from its own service: listed newest first
// whatever order the services answered in (it printed 2, 1, 3, 4, 5).
TEST(PnpctlDisplay, RunsFromSeveralServicesAreListedNewestFirst) {
  std::vector<train::v1::TrainingRun> runs(5);
  const int ids[] = {2, 1, 3, 4, 5};
  for (int k = 0; k < 5; ++k) runs[static_cast<std::size_t>(k)].set_run_id(ids[k]);
  order_newest_first(runs);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(runs[static_cast<std::size_t>(k)].run_id(), 5 - k);
}

}  // namespace
}  // namespace pnp::pnpctl
