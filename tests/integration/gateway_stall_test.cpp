// Integration: the real robot binaries with a real stall. pnp-inference-server serves the
// checked-in Panda hierarchy, pnp-robot-sim runs the simulated Panda in real time, and
// pnp-robot-gateway drives it; the controller process is then paused (SIGSTOP) in the
// middle of an episode, as a controller that stops answering is. The gateway must end
// that episode on its dead-man and go on with the next, and Ctrl-C during a stall must
// end it at once. The inference service killed mid-episode (SIGKILL) and restarted must
// cost the gateway that episode only.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>

#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"
#include "tests/integration/metrics_scrape.h"

namespace {

using pnp::integration::ChildProcess;
using pnp::integration::http_get;
using pnp::integration::metric_sum;
using pnp::integration::metrics_port;
using pnp::integration::TempDir;
using namespace std::chrono_literals;

struct RobotCell {
  explicit RobotCell(const TempDir& dir)
      : inference("inference",
                  {PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db",
                   served_store(dir)},
                  dir.path()),
        db(dir.file("pnp.db")),
        controller("robot_sim",
                   {PNP_BIN_DIR "/pnp-robot-sim", "--address", "127.0.0.1:0", "--clock", "realtime",
                    "--limits", PNP_SOURCE_DIR "/deploy/robot/controller.json"},
                   dir.path()) {}

  static std::string served_store(const TempDir& dir) {
    const std::string db = dir.file("pnp.db");
    pnp::store::RunStore store(db);
    pnp::store::import_hierarchy(store, PNP_SOURCE_DIR "/tests/data/panda_block", "panda", "block");
    return db;
  }

  void start_gateway(const TempDir& dir, int episodes, std::optional<ChildProcess>& gateway,
                     const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args{PNP_BIN_DIR "/pnp-robot-gateway",
                                  "--controller",
                                  "127.0.0.1:" + std::to_string(controller.port()),
                                  "--inference",
                                  "127.0.0.1:" + std::to_string(inference.port()),
                                  "--config",
                                  PNP_SOURCE_DIR "/deploy/robot/gateway.json",
                                  "--episodes",
                                  std::to_string(episodes),
                                  "--seed",
                                  "1000",
                                  "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    gateway.emplace("gateway", std::move(args), dir.path());
  }

  ChildProcess inference;
  std::string db;
  ChildProcess controller;
};

// Waits until the gateway has logged `count` episode starts; false after `timeout`.
bool wait_for_episode_start(ChildProcess& gateway, int count, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    const std::string log = gateway.stderr_text();
    int seen = 0;
    for (auto at = log.find("\"episode_start\""); at != std::string::npos;
         at = log.find("\"episode_start\"", at + 1)) {
      ++seen;
    }
    if (seen >= count) return true;
    std::this_thread::sleep_for(5ms);
  }
  return false;
}

// Both servers up, and a gateway for `episodes` a few cycles into its first episode.
void start_driving(RobotCell& cell, const TempDir& dir, int episodes,
                   std::optional<ChildProcess>& gateway) {
  ASSERT_GT(cell.inference.port(), 0) << cell.inference.diagnostics();
  ASSERT_GT(cell.controller.port(), 0) << cell.controller.diagnostics();
  cell.start_gateway(dir, episodes, gateway);
  ASSERT_TRUE(wait_for_episode_start(*gateway, 1, 30s)) << gateway->diagnostics();
  std::this_thread::sleep_for(200ms);
}

TEST(GatewayStall, APausedControllerEndsTheEpisodeOnTheDeadmanAndTheRunGoesOn) {
  TempDir dir("gateway_stall");
  RobotCell cell(dir);
  std::optional<ChildProcess> driving;
  ASSERT_NO_FATAL_FAILURE(start_driving(cell, dir, 3, driving));
  ChildProcess& gateway = *driving;
  cell.controller.send_signal(SIGSTOP);
  std::this_thread::sleep_for(400ms);  // four dead-man times
  cell.controller.send_signal(SIGCONT);
  const auto status = gateway.wait(60s);
  ASSERT_TRUE(status) << gateway.diagnostics();
  EXPECT_TRUE(status->ok()) << gateway.diagnostics();
  const nlohmann::json summary = nlohmann::json::parse(gateway.stdout_text());
  EXPECT_EQ(summary["episodes"], 3) << summary.dump();
  EXPECT_EQ(summary["ends"].value("deadman", 0), 1) << summary.dump();
  EXPECT_NE(gateway.stderr_text().find("did not answer"), std::string::npos)
      << gateway.diagnostics();
}

TEST(GatewayStall, CtrlCDuringAStallEndsTheGatewayAtOnce) {
  TempDir dir("gateway_stall_interrupt");
  RobotCell cell(dir);
  std::optional<ChildProcess> driving;
  ASSERT_NO_FATAL_FAILURE(start_driving(cell, dir, 50, driving));
  ChildProcess& gateway = *driving;
  cell.controller.send_signal(SIGSTOP);
  std::this_thread::sleep_for(50ms);
  const auto interrupted = std::chrono::steady_clock::now();
  gateway.send_signal(SIGINT);
  const auto status = gateway.wait(5s);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - interrupted).count();
  cell.controller.send_signal(SIGCONT);
  ASSERT_TRUE(status) << "still running 5 s after Ctrl-C\n" << gateway.diagnostics();
  EXPECT_TRUE(status->exited) << status->describe();
  EXPECT_EQ(status->code, 130) << gateway.diagnostics();
  EXPECT_LT(seconds, 1.0) << gateway.diagnostics();
}

// An operator scrapes a running gateway: the first episode's end and cycles are there by
// the time the second starts.
TEST(GatewayMetrics, AScrapeMidRunShowsTheFinishedEpisodes) {
  TempDir dir("gateway_metrics");
  RobotCell cell(dir);
  ASSERT_GT(cell.inference.port(), 0) << cell.inference.diagnostics();
  ASSERT_GT(cell.controller.port(), 0) << cell.controller.diagnostics();
  std::optional<ChildProcess> gateway;
  const std::string summary_file = dir.file("gateway.json");
  cell.start_gateway(dir, 3, gateway,
                     {"--metrics-address", "127.0.0.1:0", "--json-out", summary_file});
  ASSERT_TRUE(wait_for_episode_start(*gateway, 2, 60s)) << gateway->diagnostics();
  const int port = metrics_port(*gateway);
  ASSERT_GT(port, 0) << gateway->diagnostics();
  const std::string exposition = http_get(port, "/metrics");
  EXPECT_GE(metric_sum(exposition, "pnp_gateway_episodes_total", {}), 1.0) << exposition;
  EXPECT_GT(metric_sum(exposition, "pnp_gateway_cycle_seconds_count", {}), 0.0) << exposition;
  EXPECT_NE(exposition.find("pnp_gateway_missed_periods_total"), std::string::npos);
  const auto status = gateway->wait(120s);
  ASSERT_TRUE(status && status->ok()) << gateway->diagnostics();
  // --json-out: the summary --json prints, in a file (scripts/run's gateway.json).
  std::ifstream file(summary_file);
  ASSERT_TRUE(file) << summary_file;
  EXPECT_EQ(nlohmann::json::parse(file), nlohmann::json::parse(gateway->stdout_text()));
}

TEST(InferenceFault, AKilledInferenceServiceCostsTheEpisodeAndARestartedOneServesTheNext) {
  TempDir dir("inference_killed");
  RobotCell cell(dir);
  const int port = cell.inference.port();
  std::optional<ChildProcess> driving;
  ASSERT_NO_FATAL_FAILURE(start_driving(cell, dir, 6, driving));
  ChildProcess& gateway = *driving;
  cell.inference.kill();
  ASSERT_TRUE(cell.inference.wait(30s));
  ChildProcess restarted("inference-again",
                         {PNP_BIN_DIR "/pnp-inference-server", "--address",
                          "127.0.0.1:" + std::to_string(port), "--db", cell.db},
                         dir.path());
  ASSERT_GT(restarted.port(), 0) << restarted.diagnostics();
  const auto status = gateway.wait(120s);
  ASSERT_TRUE(status) << gateway.diagnostics();
  EXPECT_TRUE(status->ok()) << gateway.diagnostics();
  const nlohmann::json summary = nlohmann::json::parse(gateway.stdout_text());
  EXPECT_EQ(summary["episodes"], 6) << summary.dump();
  const auto& ends = summary["ends"];
  EXPECT_GE(ends.value("deadman", 0) + ends.value("controller_fault", 0), 1) << summary.dump();
  EXPECT_GE(ends.value("success", 0) + ends.value("step_cap", 0), 1)
      << "no episode after the restart completed: " << summary.dump();
}

}  // namespace
