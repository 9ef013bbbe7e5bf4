#include "bench/faults/fault_run.h"

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <atomic>
#include <map>

#include "arm_sim/controller_stand_in.h"
#include "bench/faults/arm_monitor.h"
#include "bench/faults/fault_plan.h"
#include "bench/faults/fault_switch.h"
#include "bench/faults/faulty_controller.h"
#include "bench/faults/faulty_policy.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "common/error.h"
#include "common/percentile.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "sim/panda_hand.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"

namespace pnp::faults {
namespace {

namespace rv1 = robot::v1;
using Clock = std::chrono::steady_clock;

constexpr double kMiscalibration_m = 0.03;

std::string loopback(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

std::shared_ptr<grpc::Channel> channel_to(int port) {
  return grpc::CreateChannel(loopback(port), grpc::InsecureChannelCredentials());
}

double millis(Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

struct EpisodeRecord {
  PlannedFault fault;
  gateway::EpisodeReport report;
  Clock::time_point started, ended;
  std::optional<Clock::time_point> fired;
};

// What an operator does after an emergency stop: read why, and clear it saying so.
void operator_clears_stop(rv1::RobotControllerService::Stub& controller) {
  rv1::GetStateResponse state;
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
    if (!controller.GetState(&context, {}, &state).ok()) {
      throw Error(ErrorCode::kUnavailable, "operator: GetState failed");
    }
  }
  if (state.stop_kind() != rv1::STOP_KIND_EMERGENCY) return;
  rv1::ResumeRequest request;
  request.set_acknowledged_reason(state.stop_reason());
  request.set_operator_name("pnp-bench-faults operator");
  rv1::ResumeResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  const grpc::Status status = controller.Resume(&context, request, &response);
  if (!status.ok()) {
    throw Error(ErrorCode::kFailedPrecondition,
                "operator: Resume failed: " + status.error_message());
  }
}

nlohmann::json latency_json(std::vector<double> ms) {
  if (ms.empty()) return nullptr;
  const double max = *std::max_element(ms.begin(), ms.end());
  return {{"p50", percentile(ms, 0.5)}, {"max", max}};
}

// Per fault kind: what was planned and fired, how the episodes ended and the arm was left,
// and the latencies after the fault. Counts episodes whose fault was not held in time.
nlohmann::json per_kind(const std::vector<EpisodeRecord>& records, const ArmMonitor& monitor,
                        double deadman_ms, int& not_held) {
  struct Kind {
    int planned = 0, fired = 0;
    std::map<std::string, int> ends, arm_left, controller_refusals;
    std::vector<double> hold_ms, ended_ms;
    int taken_after_deadman = 0;
  };
  std::map<std::string, Kind> kinds;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const EpisodeRecord& r = records[i];
    Kind& k = kinds[std::string(fault_kind_name(r.fault.kind))];
    ++k.planned;
    const bool whole_episode = !call_site(r.fault.kind).has_value();
    if (!whole_episode && !r.fired) continue;  // the episode ended before its call came
    ++k.fired;
    ++k.ends[std::string(gateway::episode_end_name(r.report.end))];
    for (const auto& [reason, n] : r.report.controller_refusals_by_reason) {
      k.controller_refusals[reason] += n;
    }
    ++k.arm_left[r.report.arm_left.rfind("stop not delivered", 0) == 0 ? "stop_not_delivered"
                                                                       : r.report.arm_left];
    if (whole_episode) continue;
    const Clock::time_point until = i + 1 < records.size() ? records[i + 1].started : r.ended;
    const ArmMonitor::AfterFault after = monitor.after_fault(*r.fired, until);
    k.ended_ms.push_back(millis(r.ended - *r.fired));
    const bool taken_late = after.last_taken && millis(*after.last_taken - *r.fired) > deadman_ms;
    if (taken_late) ++k.taken_after_deadman;
    if (after.held_at) k.hold_ms.push_back(millis(*after.held_at - *r.fired));
    if (taken_late || !after.held_at || millis(*after.held_at - *r.fired) > deadman_ms) {
      ++not_held;
    }
  }
  nlohmann::json out = nlohmann::json::object();
  for (auto& [name, k] : kinds) {
    out[name] = {{"planned", k.planned},
                 {"fired", k.fired},
                 {"ends", k.ends},
                 {"arm_left", k.arm_left},
                 {"controller_refusals_by_reason", k.controller_refusals},
                 {"held_after_fault_ms", latency_json(k.hold_ms)},
                 {"episode_ended_after_fault_ms", latency_json(k.ended_ms)},
                 {"targets_taken_after_deadman", k.taken_after_deadman}};
  }
  return out;
}

}  // namespace

robot::GatewayConfig miscalibrated(const robot::GatewayConfig& config) {
  robot::GatewayConfig wrong = config;
  wrong.limits.table_top_z_m -= kMiscalibration_m;
  wrong.limits.workspace.min_m.z() = sim::lowest_grip_point_z(wrong.limits.table_top_z_m);
  wrong.validate();
  return wrong;
}

nlohmann::json run_faults(const FaultRunSpec& spec) {
  if (spec.episodes < 1) {
    throw_invalid_argument("episodes", "a count >= 1", std::to_string(spec.episodes));
  }
  if (spec.stall.count() <= 0) {
    throw_invalid_argument("stall", "a positive duration", std::to_string(spec.stall.count()));
  }
  const std::vector<PlannedFault> plan = plan_faults(spec.episodes, spec.seed, spec.max_call);
  const robot::GatewayConfig wrong = miscalibrated(spec.config);

  std::filesystem::create_directories(spec.work_dir);
  const std::string db = (spec.work_dir / "pnp.db").string();
  {
    store::RunStore store(db);
    store::import_hierarchy(store, spec.checkpoints, "panda", "block");
  }
  services::PolicyServiceImpl policy_service(db);
  services::ServerRuntime policy_server({"127.0.0.1:0", 4 << 20, {&policy_service}, {}});

  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kRealTime;
  arm_sim::ControllerStandIn arm(options);
  services::RobotControllerServiceImpl controller_service(arm);
  services::SimulatedSceneServiceImpl scene_service(arm);
  services::ServerRuntime arm_server(
      {"127.0.0.1:0", 1 << 20, {&controller_service, &scene_service}, {}});

  FaultSwitch faults;
  FaultyController faulty_controller(channel_to(arm_server.port()), faults, spec.stall);
  ForwardedScene forwarded_scene(channel_to(arm_server.port()));
  FaultyPolicy faulty_policy(channel_to(policy_server.port()), faults, spec.stall);
  services::ServerRuntime proxy_server(
      {"127.0.0.1:0", 4 << 20, {&faulty_controller, &forwarded_scene, &faulty_policy}, {}});

  auto operator_stub = rv1::RobotControllerService::NewStub(channel_to(arm_server.port()));
  auto policy_stub = policy::v1::PolicyService::NewStub(channel_to(proxy_server.port()));
  std::vector<EpisodeRecord> records;
  int operator_clears = 0, lease_reacquired = 0;
  const auto run_start = Clock::now();
  nlohmann::json out;
  {
    ArmMonitor monitor(arm);
    const std::atomic<bool> never{false};
    gateway::ControllerLink link(channel_to(proxy_server.port()), loopback(proxy_server.port()),
                                 std::chrono::milliseconds(2000), never);
    const auto lease = std::chrono::milliseconds(
        static_cast<long long>(std::lround(spec.config.lease_timeout_s * 1000)));
    link.acquire_lease("pnp-bench-faults", lease);
    const auto quiet = [](std::string_view, const nlohmann::json&) {};
    gateway::GatewayEpisodeRunner planned_gateway(spec.config, link, *policy_stub, quiet);
    gateway::GatewayEpisodeRunner wrong_gateway(wrong, link, *policy_stub, quiet);
    for (int e = 0; e < spec.episodes; ++e) {
      EpisodeRecord record{plan[static_cast<std::size_t>(e)], {}, Clock::now(), {}, {}};
      const bool wrong_config = record.fault.kind == FaultKind::kMiscalibratedGateway;
      faults.arm(wrong_config ? std::nullopt : std::optional(record.fault));
      faults.set_policy_dives(wrong_config);
      gateway::EpisodeOptions episode;
      episode.seed = spec.seed + static_cast<std::uint64_t>(e);
      record.report = (wrong_config ? wrong_gateway : planned_gateway).run(episode, never);
      record.ended = Clock::now();
      record.fired = faults.fired_at();
      faults.arm(std::nullopt);
      faults.set_policy_dives(false);
      if (record.report.end == gateway::EpisodeEnd::kStopped) {
        operator_clears_stop(*operator_stub);
        ++operator_clears;
      } else if (record.report.end == gateway::EpisodeEnd::kLeaseLost) {
        link.acquire_lease("pnp-bench-faults", lease);
        ++lease_reacquired;
      }
      records.push_back(std::move(record));
    }
    const double wall_s = std::chrono::duration<double>(Clock::now() - run_start).count();

    std::vector<gateway::EpisodeReport> reports;
    for (const EpisodeRecord& r : records) reports.push_back(r.report);
    out = gateway::summarize(reports);
    int not_held = 0;
    out["faults"] = per_kind(records, monitor, spec.config.deadman_timeout_s * 1000, not_held);
    out["episodes_requested"] = spec.episodes;
    out["episodes_completed"] = records.size();
    out["faults_not_held_within_deadman"] = not_held;
    out["targets_taken"] = monitor.targets_taken();
    out["executed_outside_controller_box"] = monitor.taken_outside(options.limits.workspace);
    out["lowest_grip_z_m"] = monitor.lowest_grip_z_m();
    out["table_top_z_m"] = options.limits.table_top_z_m;
    out["operator_clears"] = operator_clears;
    out["lease_reacquired"] = lease_reacquired;
    out["deadman_ms"] = spec.config.deadman_timeout_s * 1000;
    out["stall_ms"] = spec.stall.count();
    out["seed"] = spec.seed;
    out["wall_s"] = wall_s;
  }
  proxy_server.shutdown(std::chrono::milliseconds(500));
  arm_server.shutdown(std::chrono::milliseconds(500));
  policy_server.shutdown(std::chrono::milliseconds(500));
  return out;
}

}  // namespace pnp::faults
