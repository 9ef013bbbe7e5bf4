// runs, checkpoints, metrics and plot: reading what the training services have stored.
#include <fstream>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/run_display.h"
#include "clients/pnpctl/table.h"
#include "common/error.h"
#include "common/roles.h"
#include "plot/line_chart_svg.h"
#include "pnp/train/v1/train_service.grpc.pb.h"

namespace pnp::pnpctl {
namespace {

std::vector<train::v1::MetricPoint> fetch_metrics(const Endpoints& endpoints,
                                                  const std::string& address, std::int64_t id) {
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  train::v1::GetRunMetricsRequest request;
  request.set_run_id(id);
  train::v1::GetRunMetricsResponse response;
  check(stub->GetRunMetrics(context_with_deadline().get(), request, &response), "GetRunMetrics",
        address);
  return {response.points().begin(), response.points().end()};
}

train::v1::TrainingRun fetch_run(const Endpoints& endpoints, const std::string& address,
                                 std::int64_t id) {
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  train::v1::GetTrainingRunRequest request;
  request.set_run_id(id);
  train::v1::GetTrainingRunResponse response;
  check(stub->GetTrainingRun(context_with_deadline().get(), request, &response), "GetTrainingRun",
        address);
  return response.run();
}

}  // namespace

int runs_command(const Endpoints& endpoints, const std::string& role, const std::string& state,
                 int limit, bool csv) {
  std::vector<std::string> columns = {"run",     "role",      "algorithm", "seed",
                                      "state",   "steps",     "score",     "target",
                                      "success", "to_target", "checkpoint"};
  columns.insert(columns.end(), kWallColumnNames.begin(), kWallColumnNames.end());
  columns.emplace_back("error");
  Table table(columns);
  std::vector<std::string> roles;
  if (role.empty()) {
    for (const std::string_view r : kRoles) roles.emplace_back(r);
  } else {
    endpoints.training(role);  // refuses an unknown role
    roles = {role};
  }
  std::vector<train::v1::TrainingRun> runs;
  std::string unavailable;  // the services that did not answer, for the error below
  std::size_t skipped = 0;
  for (const auto& r : roles) {
    const std::string& address = endpoints.training(r);
    auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
    train::v1::ListTrainingRunsRequest request;
    request.set_page_size(limit);
    if (!state.empty()) request.set_state(parse_state(state, "--state"));
    train::v1::ListTrainingRunsResponse response;
    const grpc::Status status = stub->ListTrainingRuns(
        context_with_deadline(std::chrono::seconds(3)).get(), request, &response);
    if (role.empty() && status.error_code() == grpc::StatusCode::UNAVAILABLE) {
      std::fprintf(stderr, "pnpctl: %s training service (%s) unavailable: skipped\n", r.c_str(),
                   address.c_str());
      unavailable += (unavailable.empty() ? "" : ", ") + r + " at " + address;
      ++skipped;
      continue;
    }
    check(status, "ListTrainingRuns", address);
    runs.insert(runs.end(), response.runs().begin(), response.runs().end());
  }
  // An empty table would read as "no runs" when nothing was asked at all.
  if (skipped == roles.size()) {
    throw Error(ErrorCode::kUnavailable,
                "no training service answered (" + unavailable +
                    "): start the platform (scripts/run) or point pnpctl at it (--approach, "
                    "--manipulate, ... or $PNP_APPROACH_ADDRESS, ...)");
  }
  order_newest_first(runs);
  for (const auto& run : runs) {
    std::vector<std::string> row = {std::to_string(run.run_id()),
                                    short_name(run.role()),
                                    short_name(run.algorithm()),
                                    std::to_string(run.seed()),
                                    outcome_text(run),
                                    std::to_string(run.env_steps()),
                                    score_text(run),
                                    fixed(run.target_success(), 2),
                                    fixed(run.last_success(), 2),
                                    run.reached() ? std::to_string(run.steps_to_target()) : "-",
                                    std::to_string(run.latest_checkpoint_id())};
    const std::vector<std::string> wall = wall_columns(run);
    row.insert(row.end(), wall.begin(), wall.end());
    row.push_back(run.error());
    table.add(row);
  }
  csv ? table.print_csv(stdout) : table.print(stdout);
  return 0;
}

int checkpoints_command(const Endpoints& endpoints, const std::string& role, std::int64_t run_id,
                        bool csv) {
  const std::string& address = endpoints.training(role);
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  train::v1::ListCheckpointsRequest request;
  request.set_run_id(run_id);
  train::v1::ListCheckpointsResponse response;
  check(stub->ListCheckpoints(context_with_deadline().get(), request, &response), "ListCheckpoints",
        address);
  Table table({"checkpoint", "run", "role", "env_steps", "eval_success", "size_bytes", "latest"});
  const int n = response.checkpoints_size();
  for (int i = 0; i < n; ++i) {
    const auto& c = response.checkpoints(i);
    table.add({std::to_string(c.checkpoint_id()), std::to_string(c.run_id()), short_name(c.role()),
               std::to_string(c.env_steps()),
               c.evaluated() ? fixed(c.eval_success(), 3) : "unevaluated",
               std::to_string(c.size_bytes()), i == n - 1 ? "latest" : ""});
  }
  csv ? table.print_csv(stdout) : table.print(stdout);
  return 0;
}

int metrics_command(const Endpoints& endpoints, const std::string& role, std::int64_t run_id,
                    bool csv) {
  Table table({"env_steps", "episodes", "wall_s", "stop_score", "task_success", "subtask_success",
               "sampled_success", "critic_loss", "actor_loss", "updates"});
  for (const auto& p : fetch_metrics(endpoints, endpoints.training(role), run_id)) {
    table.add({std::to_string(p.env_steps()), std::to_string(p.episodes()), fixed(p.wall_s(), 1),
               p.has_stop_score() ? fixed(p.stop_score(), 3) : "", fixed(p.task_success(), 3),
               fixed(p.subtask_success(), 3), fixed(p.sampled_success(), 3),
               fixed(p.critic_loss(), 5), fixed(p.actor_loss(), 5), std::to_string(p.updates())});
  }
  csv ? table.print_csv(stdout) : table.print(stdout);
  return 0;
}

int plot_command(const Endpoints& endpoints, const std::string& role,
                 const std::vector<std::int64_t>& run_ids, const std::string& metric,
                 const std::string& out) {
  if (run_ids.empty()) throw_invalid_argument("RUN", "at least one run id", "none");
  const bool score = metric == "score";
  if (!score && metric != "success")
    throw_invalid_argument("--metric", "score or success", "\"" + metric + "\"");
  const std::string& address = endpoints.training(role);
  std::vector<plot::Series> series;
  for (std::size_t i = 0; i < run_ids.size(); ++i) {
    plot::Series s{
        series_label(fetch_run(endpoints, address, run_ids[i])), plot::palette_colour(i), {}};
    for (const auto& p : fetch_metrics(endpoints, address, run_ids[i])) {
      if (score && !p.has_stop_score()) continue;  // stored before the score was kept
      s.points.emplace_back(static_cast<double>(p.env_steps()),
                            score ? p.stop_score() : p.task_success());
    }
    series.push_back(std::move(s));
  }
  plot::ChartSpec spec;
  spec.title = "Learning curves";
  spec.x_label = "training environment steps";
  spec.y_label =
      score ? "stop score (fresh evaluation episodes)" : "task success (fresh evaluation episodes)";
  std::ofstream file(out);
  if (!file) throw_invalid_argument("--out", "a writable file path", "\"" + out + "\"");
  file << plot::line_chart_svg(spec, series);
  if (!file.flush()) throw Error(ErrorCode::kUnavailable, "could not write " + out);
  std::printf("wrote %s (%zu runs)\n", out.c_str(), run_ids.size());
  return 0;
}

}  // namespace pnp::pnpctl
