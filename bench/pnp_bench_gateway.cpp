// pnp-bench-gateway: the robot gateway's cycle (controller state -> inference -> frame
// change and checks -> send) at the policy's 25 Hz against the controller stand-in in
// real time, over loopback, for at least --cycles cycles, in the served policy's world;
// beside it, in the same run, the gRPC floor: an empty unary RPC (Ping) on the same inference
// server. The served policy is the checked-in Panda hierarchy (tests/data/panda_block), or
// --checkpoints DIR.
//   cycle_p50_us, cycle_p99_us, missed_periods (cycles that overran 40 ms)
// With --bridge (a build with ROS 1), the same episodes again on the real binaries, in
// the served policy's world: pnp-robot-sim, and the real arm's chain, pnp-franka-bridge
// over a rosmaster of its own on loopback to pnp-franka-sim; "bridge" reports both and
// what the bridge adds to the cycle.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "arm_sim/simulated_arm.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "common/error.h"
#include "common/percentile.h"
#include "common/seed_flag.h"
#include "common/validate.h"
#include "robot/gateway_config.h"
#include "services/common/convert.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tools/common/cli.h"
#ifdef PNP_BENCH_BRIDGE
#include "tests/integration/child_process.h"
#include "tests/integration/ros_master.h"
#endif

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

// The world the served policy was trained in: the arms here simulate it.
sim::WorldProfile served_world(policy::v1::PolicyService::Stub& policy) {
  grpc::ClientContext context;
  policy::v1::GetServingStatusResponse status;
  if (!policy.GetServingStatus(&context, {}, &status).ok() || status.roles().empty())
    throw Error(ErrorCode::kFailedPrecondition, "GetServingStatus: no served policy");
  return services::from_proto(status.roles(0).world(), "served world");
}

// Episodes from `first_seed` on the controller at `port`, while `more` says so.
template <typename More>
std::vector<gateway::EpisodeReport> drive_at(int port, const robot::GatewayConfig& config,
                                             policy::v1::PolicyService::Stub& policy,
                                             std::uint64_t first_seed, More more,
                                             double* state_hot_us = nullptr) {
  std::vector<gateway::EpisodeReport> reports;
  const std::atomic<bool> never{false};
  gateway::ControllerLink controller(
      grpc::CreateChannel(loopback(port), grpc::InsecureChannelCredentials()), loopback(port),
      std::chrono::milliseconds(2000), never);
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
  return reports;
}

// The same on a fresh in-process stand-in with `clock`.
template <typename More>
std::vector<gateway::EpisodeReport> drive(const robot::GatewayConfig& config,
                                          policy::v1::PolicyService::Stub& policy,
                                          arm_sim::ClockMode clock, double acceleration_scale,
                                          std::uint64_t first_seed, More more,
                                          double* state_hot_us = nullptr) {
  arm_sim::StandInOptions options;
  options.clock = clock;
  options.world = served_world(policy);
  options.arm.acceleration_limits_rad_per_s2 =
      arm_sim::arm_accelerations(acceleration_scale, "--acceleration-scale");
  arm_sim::ControllerStandIn arm(options);
  services::RobotControllerServiceImpl controller_service(arm);
  services::SimulatedSceneServiceImpl scene_service(arm);
  services::ServerRuntime server(
      {"127.0.0.1:0", 1 << 20, {&controller_service, &scene_service}, {}});
  auto reports = drive_at(server.port(), config, policy, first_seed, more, state_hot_us);
  server.shutdown(std::chrono::milliseconds(500));
  return reports;
}

#ifdef PNP_BENCH_BRIDGE
// `episodes` episodes from `first_seed`, in real time, on pnp-robot-sim and through
// pnp-franka-bridge to pnp-franka-sim, both in the served policy's world; their summaries
// and what the bridge adds to the cycle.
nlohmann::json compare_with_bridge(const robot::GatewayConfig& config,
                                   policy::v1::PolicyService::Stub& policy,
                                   std::uint64_t first_seed, std::size_t episodes,
                                   const std::filesystem::path& dir) {
  using integration::ChildProcess;
  const std::string bin = PNP_BIN_DIR;
  const std::string limits = PNP_DEFAULT_CONTROLLER_LIMITS;
  const std::string world(sim::world_profile_name(served_world(policy)));
  const auto enough = [&](const std::vector<gateway::EpisodeReport>& so_far) {
    return so_far.size() < episodes;
  };
  const auto port_of = [](ChildProcess& child) {
    const int port = child.port();
    if (port <= 0) throw std::runtime_error(child.diagnostics());
    return port;
  };
  ChildProcess robot_sim("robot_sim",
                         {bin + "/pnp-robot-sim", "--address", "127.0.0.1:0", "--clock", "realtime",
                          "--world", world, "--limits", limits},
                         dir);
  const auto direct = drive_at(port_of(robot_sim), config, policy, first_seed, enough);
  robot_sim.terminate_and_wait();

  const integration::RosMaster master(dir);
  ChildProcess franka_sim("franka_sim",
                          {bin + "/pnp-franka-sim", "--world", world, "--address", "127.0.0.1:0"},
                          dir, master.node_env());
  ChildProcess bridge("franka_bridge",
                      {bin + "/pnp-franka-bridge", "--address", "127.0.0.1:0", "--limits", limits,
                       "--stand-in-scene", loopback(port_of(franka_sim))},
                      dir, master.node_env());
  const int bridge_port = port_of(bridge);
  {  // Ready once the bridge has the arm's state.
    const std::atomic<bool> never{false};
    gateway::ControllerLink link(
        grpc::CreateChannel(loopback(bridge_port), grpc::InsecureChannelCredentials()),
        loopback(bridge_port), std::chrono::milliseconds(2000), never);
    if (!integration::wait_until(
            [&] { return link.state().state().mode() == robot::v1::CONTROLLER_MODE_IDLE; },
            std::chrono::seconds(30)))
      throw std::runtime_error("the bridge never had the arm's state: " + bridge.diagnostics());
  }
  double bridge_state_hot_us = 0;
  const auto bridged =
      drive_at(bridge_port, config, policy, first_seed, enough, &bridge_state_hot_us);
  bridge.terminate_and_wait();
  franka_sim.terminate_and_wait();

  nlohmann::json out{{"world", world},
                     {"robot_sim", gateway::summarize(direct)},
                     {"bridge", gateway::summarize(bridged)},
                     {"bridge_state_back_to_back_p50_us", bridge_state_hot_us}};
  for (const char* field : {"cycle_p50_us", "cycle_p99_us", "state_p50_us", "send_p50_us"}) {
    out[std::string("added_") + field] =
        out["bridge"][field].get<double>() - out["robot_sim"][field].get<double>();
  }
  return out;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Robot gateway cycle latency against the controller stand-in in real time",
               "pnp-bench-gateway"};
  int cycles = 2000;
  std::string checkpoints = PNP_DEFAULT_CHECKPOINTS;
  std::string config_path = PNP_DEFAULT_GATEWAY_CONFIG;
  std::uint64_t seed = 5000;
  bool json = false, bridge = false;
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
  app.add_flag("--bridge", bridge,
               "also the same episodes on pnp-robot-sim and through pnp-franka-bridge to "
               "pnp-franka-sim (needs a build with ROS 1)");
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
    nlohmann::json bridge_comparison;
    if (bridge) {
#ifdef PNP_BENCH_BRIDGE
      bridge_comparison = compare_with_bridge(config, *policy_stub, seed, reports.size(), dir);
#else
      throw Error(ErrorCode::kFailedPrecondition,
                  "--bridge: this build has no ROS 1 (configure with -DPNP_ROS=ON)");
#endif
    }
    policy_server.shutdown(std::chrono::milliseconds(500));
    std::filesystem::remove_all(dir);

    nlohmann::json out = gateway::summarize(reports);
    if (bridge) out["bridge"] = bridge_comparison;
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
