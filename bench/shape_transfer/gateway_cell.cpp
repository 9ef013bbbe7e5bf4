#include "bench/shape_transfer/gateway_cell.h"

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <vector>

#include "arm_sim/arm_actuated_env.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "nn/checkpoint_io.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "sim/world_model.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"

namespace pnp::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::string loopback(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

// A fresh store in `dir` with the served checkpoints imported and promoted.
std::string make_store(const std::filesystem::path& dir, const ServedCheckpoints& served) {
  std::filesystem::create_directories(dir);
  const std::filesystem::path db = dir / "pnp.db";
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db.string() + suffix);
  store::RunStore store(db.string());
  auto import = [&](const std::string& role, const std::string& algorithm, sim::ObjectShape object,
                    const training::Blob& blob) {
    const std::filesystem::path file = dir / (role + ".ckpt");
    nn::write_file_atomically(file.string(), blob);
    store::import_checkpoint(
        store, {role, algorithm, "panda", std::string(sim::object_name(object)), file}, true);
  };
  if (served.kind == serving::PolicyKind::kEndToEnd) {
    import("e2e", "ddpg_her", sim::ObjectShape::kBlock, served.e2e);
  } else {
    for (std::size_t k = 0; k < kHierarchyRoles.size(); ++k) {
      const std::string role = kHierarchyRoles[k];
      import(role, role == "hlc" ? "a3c" : "ddpg_her", served.hierarchy.objects[k],
             served.hierarchy.roles[k]);
    }
  }
  return db.string();
}

// Episodes from `next` on, on a fresh controller stand-in, until `last` or until the
// gateway refuses a reading (an exception: that episode is recorded as a failure with its
// reason). Returns the seed to go on from.
std::uint64_t play_segment(const GatewayCellSpec& spec, policy::v1::PolicyService::Stub& policy,
                           std::uint64_t next, std::uint64_t last,
                           std::vector<gateway::EpisodeReport>& reports,
                           nlohmann::json& gateway_errors, std::ofstream& events) {
  arm_sim::StandInOptions options;
  options.object = spec.shape;
  options.world = spec.world;
  options.clock = arm_sim::ClockMode::kLockstep;
  options.arm.acceleration_limits_rad_per_s2 =
      arm_sim::arm_accelerations(spec.acceleration_scale, "--acceleration-scale");
  arm_sim::ControllerStandIn arm(options);
  services::RobotControllerServiceImpl controller_service(arm);
  services::SimulatedSceneServiceImpl scene_service(arm);
  services::ServerRuntime server(
      {"127.0.0.1:0", 1 << 20, {&controller_service, &scene_service}, {}});
  {
    const std::atomic<bool> never{false};
    gateway::ControllerLink controller(
        grpc::CreateChannel(loopback(server.port()), grpc::InsecureChannelCredentials()),
        loopback(server.port()), std::chrono::milliseconds(2000), never);
    controller.acquire_lease(
        "pnp-shape-transfer",
        std::chrono::milliseconds(static_cast<long long>((*spec.config).lease_timeout_s * 1000)));
    gateway::GatewayEpisodeRunner runner(*spec.config, controller, policy,
                                         [&](std::string_view event, const nlohmann::json& fields) {
                                           nlohmann::json line = fields;
                                           line["event"] = event;
                                           events << line.dump() << "\n";
                                         });
    for (; next <= last; ++next) {
      try {
        gateway::EpisodeOptions episode;
        episode.seed = next;
        episode.trace = true;  // the events file is the cell's failure analysis
        reports.push_back(runner.run(episode, never));
        if (gateway::ends_run(reports.back().end)) {  // a fresh stand-in for the rest
          gateway_errors.push_back({{"seed", next}, {"error", reports.back().reason}});
          ++next;
          break;
        }
      } catch (const std::exception& e) {
        gateway::EpisodeReport failed;
        failed.seed = next;
        failed.end = gateway::EpisodeEnd::kControllerFault;
        failed.reason = e.what();
        reports.push_back(failed);
        gateway_errors.push_back({{"seed", next}, {"error", e.what()}});
        ++next;
        break;
      }
    }
  }
  server.shutdown(std::chrono::milliseconds(500));
  return next;
}

// The same scenes in the arm-actuated world (what training evaluates on), with the same
// served policy: the world's success at the episode's end, and at any step (the gateway stops at
// the first success, so this is what it should report), and the scenes where the gateway and the
// world disagree.
nlohmann::json play_arm_world(const GatewayCellSpec& spec, const std::string& db,
                              serving::PolicyKind kind,
                              const std::vector<gateway::EpisodeReport>& gateway) {
  std::shared_ptr<const serving::ServedPolicy> served;
  {
    store::RunStore store(db);
    served = serving::load_promoted(store, store.promotions(), kind);
  }
  arm_sim::ArmWorldOptions options;
  options.arm.acceleration_limits_rad_per_s2 =
      arm_sim::arm_accelerations(spec.acceleration_scale, "--acceleration-scale");
  arm_sim::ArmActuatedEnv env(sim::WorldModel::load(sim::Robot::kPanda, spec.shape, spec.world),
                              options);
  int at_end = 0, any_step = 0;
  nlohmann::json disagreements = nlohmann::json::array();
  for (const gateway::EpisodeReport& report : gateway) {
    const serving::ServedPolicy::Lease controller = served->acquire(env.episode_steps());
    sim::StepResult step;
    step.observation = env.reset(report.seed);
    bool reached = sim::is_task_success(sim::object_position(step.observation), env.episode_goal());
    while (!env.needs_reset()) {
      const serving::Decision d = controller->act(step.observation, env.episode_goal());
      step = env.step(d.action, env.episode_goal(), sim::Objective::kTask);
      reached = reached || step.task_success;
    }
    at_end += step.task_success ? 1 : 0;
    any_step += reached ? 1 : 0;
    if (reached != report.success) {
      disagreements.push_back({{"seed", report.seed},
                               {"gateway", report.success},
                               {"gateway_end", gateway::episode_end_name(report.end)},
                               {"arm_world_any_step", reached}});
    }
  }
  const double n = gateway.empty() ? 1.0 : static_cast<double>(gateway.size());
  return {{"success_at_episode_end", at_end / n},
          {"success_any_step", any_step / n},
          {"disagreements_with_gateway", disagreements}};
}

}  // namespace

nlohmann::json play_gateway_cell(const GatewayCellSpec& spec, const ServedCheckpoints& served) {
  const auto start = Clock::now();
  const std::string db = make_store(spec.work_dir, served);
  services::PolicyServiceImpl policy_service(db, served.kind);
  services::ServerRuntime policy_server({"127.0.0.1:0", 4 << 20, {&policy_service}, {}});
  auto policy = policy::v1::PolicyService::NewStub(
      grpc::CreateChannel(loopback(policy_server.port()), grpc::InsecureChannelCredentials()));
  std::vector<gateway::EpisodeReport> reports;
  nlohmann::json gateway_errors = nlohmann::json::array();
  std::ofstream events(spec.work_dir / "gateway_events.jsonl");
  const std::uint64_t last = spec.first_seed + static_cast<std::uint64_t>(spec.episodes) - 1;
  for (std::uint64_t next = spec.first_seed; next <= last;)
    next = play_segment(spec, *policy, next, last, reports, gateway_errors, events);
  policy_server.shutdown(std::chrono::milliseconds(500));

  nlohmann::json out = gateway::summarize(reports);
  int solved_at_start = 0;
  for (const auto& r : reports) solved_at_start += (r.success && r.steps == 0) ? 1 : 0;
  out["gateway_errors"] = gateway_errors;
  out["solved_at_start"] = solved_at_start;
  out["arm_world"] = play_arm_world(spec, db, served.kind, reports);
  out["wall_s"] = std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

}  // namespace pnp::bench
