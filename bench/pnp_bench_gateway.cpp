// pnp-bench-gateway: the robot gateway's cycle (controller state -> inference -> frame
// change and checks -> send) at the policy's 25 Hz against the controller stand-in in
// real time, over loopback, for at least --cycles cycles; beside it, in the same run, the
// gRPC floor: an empty unary RPC (Ping) on the same inference server. The served policy
// is the checked-in Panda hierarchy (tests/data/panda_block), or --checkpoints DIR.
//   cycle_p50_us, cycle_p99_us, missed_periods (cycles that overran 40 ms)

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "arm_sim/simulated_arm.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "common/percentile.h"
#include "common/seed_flag.h"
#include "common/validate.h"
#include "robot/gateway_config.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tools/common/cli.h"

namespace {

using namespace pnp;
using Clock = std::chrono::steady_clock;

std::string loopback(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

double ping_p50_us(int port, int calls) {
  auto stub = policy::v1::PolicyService::NewStub(
      grpc::CreateChannel(loopback(port), grpc::InsecureChannelCredentials()));
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(calls));
  for (int k = 0; k < calls; ++k) {
    grpc::ClientContext context;
    policy::v1::PingResponse response;
    const auto start = Clock::now();
    if (!stub->Ping(&context, {}, &response).ok()) throw std::runtime_error("Ping failed");
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  return percentile(std::move(us), 0.5);
}

// GetState back to back: the state read's own cost, without the cycle's idle wait.
double get_state_p50_us(gateway::ControllerLink& controller, int calls) {
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(calls));
  for (int k = 0; k < calls; ++k) {
    const auto start = Clock::now();
    controller.state();
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  return percentile(std::move(us), 0.5);
}

// Episodes from `first_seed` on a fresh stand-in with `clock`, while `more` says so.
template <typename More>
std::vector<gateway::EpisodeReport> drive(const robot::GatewayConfig& config,
                                          policy::v1::PolicyService::Stub& policy,
                                          arm_sim::ClockMode clock, double acceleration_scale,
                                          std::uint64_t first_seed, More more,
                                          double* state_hot_us = nullptr) {
  arm_sim::StandInOptions options;
  options.clock = clock;
  options.arm.acceleration_limits_rad_per_s2 =
      arm_sim::arm_accelerations(acceleration_scale, "--acceleration-scale");
  arm_sim::ControllerStandIn arm(options);
  services::RobotControllerServiceImpl controller_service(arm);
  services::SimulatedSceneServiceImpl scene_service(arm);
  services::ServerRuntime server(
      {"127.0.0.1:0", 1 << 20, {&controller_service, &scene_service}, {}});
  std::vector<gateway::EpisodeReport> reports;
  {
    const std::atomic<bool> never{false};
    gateway::ControllerLink controller(
        grpc::CreateChannel(loopback(server.port()), grpc::InsecureChannelCredentials()),
        loopback(server.port()), std::chrono::milliseconds(2000), never);
    controller.acquire_lease(
        "pnp-bench-gateway",
        std::chrono::milliseconds(static_cast<long long>(config.lease_timeout_s * 1000)));
    if (state_hot_us) *state_hot_us = get_state_p50_us(controller, 500);
    gateway::GatewayEpisodeRunner runner(config, controller, policy,
                                         [](std::string_view, const nlohmann::json&) {});
    do {
      gateway::EpisodeOptions episode;
      episode.seed = first_seed + reports.size();
      reports.push_back(runner.run(episode, never));
    } while (!gateway::ends_run(reports.back().end) && more(reports));
  }
  server.shutdown(std::chrono::milliseconds(500));
  return reports;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Robot gateway cycle latency against the controller stand-in in real time",
               "pnp-bench-gateway"};
  int cycles = 2000;
  std::string checkpoints = PNP_DEFAULT_CHECKPOINTS;
  std::string config_path = PNP_DEFAULT_GATEWAY_CONFIG;
  std::uint64_t seed = 5000;
  bool json = false;
  double acceleration_scale = arm_sim::kDefaultAccelerationScale;
  app.add_option("--cycles", cycles, "at least this many gateway cycles")->capture_default_str();
  app.add_option("--checkpoints", checkpoints, "directory with {approach,...,hlc}.ckpt (panda)")
      ->capture_default_str();
  app.add_option("--config", config_path, "gateway config")->capture_default_str();
  app.add_option("--seed", seed, "first episode seed")
      ->check(pnp::seed_value())
      ->capture_default_str();
  app.add_option("--acceleration-scale", acceleration_scale,
                 "the simulated Panda's joint accelerations, x its datasheet's")
      ->capture_default_str();
  app.add_flag("--json", json, "print one JSON object");
  return tools::run_tool(app, argc, argv, [&] {
    require_positive(cycles, "--cycles");
    arm_sim::arm_accelerations(acceleration_scale, "--acceleration-scale");
    const robot::GatewayConfig config = robot::GatewayConfig::load(config_path);
    const auto dir = std::filesystem::temp_directory_path() /
                     ("pnp_bench_gateway_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string db = (dir / "pnp.db").string();
    {
      store::RunStore store(db);
      store::import_hierarchy(store, checkpoints, "panda", "block");
    }
    services::PolicyServiceImpl policy_service(db);
    services::ServerRuntime policy_server({"127.0.0.1:0", 4 << 20, {&policy_service}, {}});
    auto policy_stub = policy::v1::PolicyService::NewStub(
        grpc::CreateChannel(loopback(policy_server.port()), grpc::InsecureChannelCredentials()));
    const double floor_before = ping_p50_us(policy_server.port(), 500);

    // Real time: the latency figures (and success with the arm on the wall clock).
    double state_hot_us = 0;
    std::size_t done = 0;
    const auto start = Clock::now();
    const auto reports = drive(
        config, *policy_stub, arm_sim::ClockMode::kRealTime, acceleration_scale, seed,
        [&](const std::vector<gateway::EpisodeReport>& so_far) {
          done += so_far.back().cycle_us.size();
          return done < static_cast<std::size_t>(cycles);
        },
        &state_hot_us);
    const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    const double floor_after = ping_p50_us(policy_server.port(), 500);
    // The same episodes in lockstep: the physics without the wall clock, the success peer.
    const auto lockstep =
        drive(config, *policy_stub, arm_sim::ClockMode::kLockstep, acceleration_scale, seed,
              [&](const std::vector<gateway::EpisodeReport>& so_far) {
                return so_far.size() < reports.size();
              });
    policy_server.shutdown(std::chrono::milliseconds(500));
    std::filesystem::remove_all(dir);

    nlohmann::json out = gateway::summarize(reports);
    const double floor = std::min(floor_before, floor_after);
    out["floor_p50_us"] = floor;
    out["cycle_p50_over_floor"] = out["cycle_p50_us"].get<double>() / floor;
    out["state_back_to_back_p50_us"] = state_hot_us;
    out["lockstep_success_rate"] = gateway::summarize(lockstep)["success_rate"];
    out["wall_s"] = wall_s;
    out["period_ms"] = config.policy_period_s * 1000;
    out["acceleration_scale"] = acceleration_scale;
    std::cout << (json ? out.dump() : out.dump(2)) << "\n";
  });
}
