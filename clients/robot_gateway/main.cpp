// pnp-robot-gateway: drives an arm with the served policy. Each cycle (25 Hz) reads the
// controller's state, asks the inference service for the next action, changes the target
// into the arm's base frame (config: deploy/robot/gateway.json), checks it and streams it.
//   --controller 127.0.0.1:50070 --inference 127.0.0.1:50060 --config deploy/robot/gateway.json
//   --episodes 5 --seed 1000 [--dry-run [--controller-limits FILE]] [--record FILE] [--view DIR]
//   [--trace] [--json] [--strict] [--await-operator S]
//   [--tls-ca FILE [--tls-cert FILE --tls-key FILE] [--token-file FILE]]  (both services)
// Ctrl-C emergency-stops the arm within one policy period and ends the run (an operator
// clears the stop: pnpctl robot resume --ack REASON); a second Ctrl-C exits at once. Any
// other emergency stop (a reflex, a stalled arm, anyone's E-stop) ends the run too, unless
// --await-operator gives the operator time to clear it: then the run goes on.

#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <thread>

#include "clients/robot_gateway/dry_run.h"
#include "clients/robot_gateway/episode_view.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_metrics.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "clients/robot_gateway/operator_wait.h"
#include "clients/robot_gateway/target_record.h"
#include "common/error.h"
#include "common/seed_flag.h"
#include "common/version.h"
#include "services/common/address.h"
#include "services/common/client_logging.h"
#include "services/common/endpoints_file.h"
#include "services/common/replica_channel.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"

namespace {

void write_json_file(const std::string& path, const nlohmann::json& value) {
  std::ofstream file(path);
  file << value.dump(2) << "\n";
  if (!file.flush())
    throw pnp::Error(pnp::ErrorCode::kUnavailable, "--json-out: could not write " + path);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pnp;
  services::quiet_grpc_logs_unless_asked();
  services::catch_termination_signals();  // handed to the watcher below
  CLI::App app{"Drive an arm's controller with the served pick-and-place policy",
               "pnp-robot-gateway"};
  std::string controller_address = "127.0.0.1:50070";
  std::string inference_address = "127.0.0.1:50060";
  std::string config_path = "deploy/robot/gateway.json";
  std::string name = "pnp-robot-gateway";
  int episodes = 5;
  std::uint64_t seed = 1000;
  bool dry_run = false, trace = false, json = false, quiet = false, public_metrics = false;
  bool strict = false;
  double await_operator_s = 0;
  std::string metrics_address;
  app.add_option("--controller", controller_address, "robot controller host:port")
      ->envname("PNP_ROBOT_CONTROLLER_ADDRESS")
      ->capture_default_str();
  app.add_option("--inference", inference_address, "inference service host:port")
      ->envname("PNP_INFERENCE_ADDRESS")
      ->capture_default_str();
  std::string endpoints_file;
  services::add_endpoints_file_option(app, endpoints_file);
  app.add_option("--config", config_path, "gateway config (frames, limits, timing)")
      ->capture_default_str();
  app.add_option("--episodes", episodes, "episodes to run")->capture_default_str();
  app.add_option("--seed", seed, "first episode's scene seed (then seed+1, ...)")
      ->check(pnp::seed_value())
      ->capture_default_str();
  std::vector<double> goal;
  app.add_option("--goal", goal,
                 "a real arm's episode: the goal X,Y,Z (base frame, metres) for the object the "
                 "controller perceives where the operator placed it; no scene reset, one episode")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--name", name, "client name on the lease")->capture_default_str();
  app.add_flag("--dry-run", dry_run,
               "play each episode on a shadow of the arm (the simulated Panda, from the live "
               "arm's state and object) while the live arm holds; nothing is sent to it");
  std::string controller_limits = "deploy/robot/controller.json";
  app.add_option("--controller-limits", controller_limits,
                 "a dry run's shadow checks every target against these: the live controller's "
                 "own limits (its --limits file)")
      ->capture_default_str();
  std::string record_path;
  app.add_option("--record", record_path,
                 "write every target sent (in a dry run: that would be sent) as JSON lines");
  std::string view_dir;
  app.add_option("--view", view_dir,
                 "write each episode's view (grip point path by subtask, object, goal) as "
                 "DIR/episode_SEED.svg");
  app.add_flag("--trace", trace,
               "log a cycle event every cycle: grip point, object, subtask, action, target");
  app.add_flag("--json", json, "print the summary as one JSON object");
  std::string json_out;
  app.add_option("--json-out", json_out, "also write the summary as JSON to this file");
  app.add_flag("--quiet", quiet, "no per-event log lines on stderr (warnings still)");
  app.add_flag("--strict", strict,
               "refuse a served policy trained for another arm (another robot, or the mocap "
               "hand instead of the arm's controller) instead of warning");
  app.add_option("--await-operator", await_operator_s,
                 "after an emergency stop, wait up to this many seconds for an operator to clear "
                 "it (pnpctl robot resume --ack REASON), then go on with the next episode (0: the "
                 "run ends)")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one, logged as metrics_port; "
                 "empty: off)");
  app.add_flag("--public-metrics", public_metrics,
               "allow /metrics (plaintext HTTP, read-only counters) on a non-loopback address");
  services::ClientTlsFiles tls;  // the controller's and the inference service's
  services::add_client_security_flags(app, tls);
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  try {
    if (episodes < 1) {
      throw_invalid_argument("--episodes", "a positive integer", std::to_string(episodes));
    }
    if (!goal.empty() && episodes != 1) {
      throw_invalid_argument("--episodes",
                             "1 with --goal (the operator places the object for "
                             "each episode)",
                             std::to_string(episodes));
    }
    const services::FileAddress from_file[] = {
        {"robot_controller", "--controller", &controller_address},
        {"inference", "--inference", &inference_address}};
    endpoints_file = services::apply_endpoints_file(app, endpoints_file, from_file);
    services::validate_address(controller_address, "--controller");
    services::validate_address(inference_address, "--inference");
    services::validate(tls);
    if (!metrics_address.empty() && !services::is_loopback_address(metrics_address) &&
        !public_metrics)
      throw Error(ErrorCode::kFailedPrecondition,
                  "--metrics-address " + metrics_address +
                      " is beyond loopback: pass --public-metrics (its counters are public)");
    const robot::GatewayConfig config = robot::GatewayConfig::load(config_path);
    services::MetricsRegistry metrics;
    gateway::GatewayMetrics episode_metrics(metrics);
    std::optional<services::MetricsHttpServer> metrics_http;
    if (!metrics_address.empty()) {
      metrics_http.emplace(metrics_address, metrics);
      services::log_event("gateway", "listening", {{"metrics_port", metrics_http->port()}});
    }
    // Ctrl-C or SIGTERM: the running episode stops the arm and ends; a second one exits
    // at once (the arm's own dead-man, the lease, then holds it).
    std::atomic<bool> interrupted{false}, finished{false};
    std::jthread watcher([&] {
      services::wait_for_termination_signal();
      if (finished.load()) return;
      interrupted.store(true);
      services::wait_for_termination_signal();
      if (finished.load()) return;
      std::fputs("pnp-robot-gateway: second interrupt: exiting now\n", stderr);
      std::_Exit(130);
    });
    struct WakeWatcher {  // on every way out: release the watcher so it can be joined
      std::atomic<bool>& finished;
      ~WakeWatcher() {
        finished.store(true);
        ::kill(::getpid(), SIGTERM);
      }
    } wake{finished};
    const auto timeout = std::chrono::milliseconds(2000);
    auto controller_channel = services::dial(controller_address, tls);
    // A restarted inference service is found again within 0.1-1 s (gRPC's default
    // backoff grows to 120 s), so the next episode need not wait long for it.
    grpc::ChannelArguments inference_args;
    inference_args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
    inference_args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 100);
    inference_args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 1000);
    services::balance_over_replicas(inference_args);  // a session stays on its replica
    auto inference_channel = services::dial(inference_address, tls, inference_args);
    for (auto& [channel, address] : {std::pair{controller_channel, controller_address},
                                     std::pair{inference_channel, inference_address}}) {
      if (!channel->WaitForConnected(std::chrono::system_clock::now() + timeout)) {
        throw Error(ErrorCode::kUnavailable, address + ": not reachable within 2 s");
      }
    }
    gateway::ControllerLink controller(controller_channel, controller_address, timeout,
                                       interrupted);
    auto policy = policy::v1::PolicyService::NewStub(inference_channel);
    controller.acquire_lease(name, std::chrono::milliseconds(static_cast<long long>(
                                       std::lround(config.lease_timeout_s * 1000))));
    gateway::EventLog log = [&](std::string_view event, const nlohmann::json& fields) {
      if (!quiet || event == "policy_warning") services::log_event("gateway", event, fields);
    };
    std::optional<gateway::TargetRecord> record;
    if (!record_path.empty()) record.emplace(record_path);
    std::optional<gateway::DryRun> dry;
    std::optional<gateway::GatewayEpisodeRunner> runner;
    if (dry_run) {
      dry.emplace(config, robot::ControllerLimits::load(controller_limits), controller, *policy,
                  log, strict, interrupted);
    } else {
      runner.emplace(config, controller, *policy, log, strict);
    }
    std::vector<gateway::EpisodeReport> reports;
    for (int k = 0; k < episodes && !interrupted.load(); ++k) {
      gateway::EpisodeOptions options{
          .seed = seed + static_cast<std::uint64_t>(k),
          .reset_scene = goal.empty(),
          .goal_base = goal.empty() ? std::nullopt
                                    : std::optional<Eigen::Vector3d>({goal[0], goal[1], goal[2]}),
          .trace = trace,
          .watch = {},
          .record = {}};
      if (record) {
        options.record = [&record](std::uint64_t s, int step, const robot::PoseTarget& t) {
          record->add(s, step, t);
        };
      }
      reports.push_back(dry ? dry->run(options, interrupted) : runner->run(options, interrupted));
      if (!view_dir.empty()) {
        log("episode_view",
            {{"path", gateway::write_episode_view(view_dir, reports.back(), dry_run).string()}});
      }
      episode_metrics.record(reports.back());
      const bool cleared =
          reports.back().end == gateway::EpisodeEnd::kStopped && await_operator_s > 0 &&
          k + 1 < episodes &&
          gateway::wait_for_operator(
              controller, std::chrono::milliseconds(std::lround(await_operator_s * 1000)),
              interrupted, log) == gateway::OperatorWait::kCleared;
      if (gateway::ends_run(reports.back().end) && !cleared) {
        std::fprintf(stderr, "pnp-robot-gateway: run ended: %s\n", reports.back().reason.c_str());
        break;
      }
    }
    const nlohmann::json summary = gateway::summarize(reports);
    if (!json_out.empty()) write_json_file(json_out, summary);
    if (json) {
      std::cout << summary.dump() << "\n";
    } else {
      std::printf(
          "%d/%zu episodes succeeded (%d requested); cycle p50 %.0f us, p99 %.0f us; %d missed "
          "periods; %d targets refused\n",
          summary["successes"].get<int>(), reports.size(), episodes,
          summary["cycle_p50_us"].get<double>(), summary["cycle_p99_us"].get<double>(),
          summary["missed_periods"].get<int>(), summary["refused_targets"].get<int>());
    }
    if (interrupted.load()) return 130;
    return !reports.empty() && gateway::ends_run(reports.back().end) ? 3 : 0;
  } catch (const Error& e) {
    const std::string message = e.code() == ErrorCode::kUnavailable
                                    ? services::with_endpoints_file_hint(endpoints_file, e.what())
                                    : std::string(e.what());
    std::fprintf(stderr, "pnp-robot-gateway: %s\n", message.c_str());
    return e.code() == ErrorCode::kInvalidArgument ? 2 : 1;  // 2: bad usage or input
  }
}
