// pnp-robot-sim: the robot controller stand-in. The simulated Panda of core/arm_sim behind
// pnp.robot.v1.RobotControllerService (and SimulatedSceneService to start seeded
// episodes), for driving with pnp-robot-gateway without hardware.
//   --address 127.0.0.1:50070  --object block  --clock realtime|lockstep
//   [--limits deploy/robot/controller.json] [--metrics-address 127.0.0.1:9107]
//   [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]] [--auth-policy FILE] [--insecure]
//   [--audit-db FILE | --store HOST:PORT]  (docs/RELIABILITY.md, "Who may do what")
// The limits file is the controller's own (workspace, table plane, step, speed, target
// age): nothing over the network changes it.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>

#include "arm_sim/simulated_arm.h"
#include "common/error.h"
#include "common/version.h"
#include "services/common/metrics_registry.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "services/store/remote_audit.h"
#include "services/store/store_flags.h"

int main(int argc, char** argv) {
  using namespace pnp::services;
  catch_termination_signals();
  CLI::App app{"Simulated Franka Panda controller (1 kHz joint-space tracking)", "pnp-robot-sim"};
  std::string address = "127.0.0.1:50070";
  std::string object = "block";
  std::string clock = "realtime";
  std::string world(pnp::sim::world_profile_name(pnp::sim::kDefaultWorldProfile));
  std::string metrics_address, limits;
  double acceleration_scale = pnp::arm_sim::kDefaultAccelerationScale;
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--object", object, "object on the table: block, cylinder or small_block")
      ->capture_default_str();
  app.add_option("--world", world, "world profile: paper or gym (docs/SIMULATION.md)")
      ->capture_default_str();
  app.add_option("--clock", clock,
                 "realtime: the 1 kHz loop runs on the wall clock, as an arm does; lockstep: "
                 "one policy period of physics per target (fast evaluations)")
      ->check(CLI::IsMember({"realtime", "lockstep"}))
      ->capture_default_str();
  app.add_option("--limits", limits,
                 "the controller's own limits, JSON (deploy/robot/controller.json; empty: its "
                 "defaults, the same values)");
  app.add_option("--acceleration-scale", acceleration_scale,
                 "the simulated Panda's joint accelerations, x its datasheet's")
      ->capture_default_str();
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  ServerSecurityFlags security_flags;
  add_server_security_flags(app, security_flags, /*audit_db_flag=*/true);
  // The audit through pnp-store-server instead of a file: every robot call lands in the
  // platform's one audit table.
  RemoteStoreFlags store_flags;
  add_remote_store_flags(app, store_flags, app.get_option("--audit-db"));
  StreamLimitOptions limit_options;
  double idle_timeout_s = 0;
  add_stream_limit_flags(app, limit_options, idle_timeout_s);
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  try {
    ServerSecurity security = load_server_security(security_flags, address, metrics_address);
    const auto audit =
        store_flags.remote()
            ? open_remote_audit_trail(store_flags.address, store_flags.tls, "robot_sim")
            : open_audit_trail(security_flags.audit_db, "robot_sim");
    security.audit = audit.get();
    pnp::arm_sim::StandInOptions options;
    options.object = pnp::sim::parse_object(object, "--object");
    options.world = pnp::sim::parse_world_profile(world, "--world");
    options.clock = clock == "lockstep" ? pnp::arm_sim::ClockMode::kLockstep
                                        : pnp::arm_sim::ClockMode::kRealTime;
    options.arm.acceleration_limits_rad_per_s2 =
        pnp::arm_sim::arm_accelerations(acceleration_scale, "--acceleration-scale");
    if (!limits.empty()) options.limits = pnp::robot::ControllerLimits::load(limits);
    pnp::arm_sim::ControllerStandIn arm(options);
    StreamLimits stream_limits(stream_limit_options(limit_options, idle_timeout_s), "robot_sim");
    RobotControllerServiceImpl controller(arm, &stream_limits);
    SimulatedSceneServiceImpl scene(arm);
    MetricsRegistry metrics;
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 1 << 20,
                           .services = {&controller, &scene},
                           .service_names = {"pnp.robot.v1.RobotControllerService",
                                             "pnp.robot.v1.SimulatedSceneService"},
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address,
                           .security = security,
                           .log_name = "robot_sim"});
    return serve_until_terminated(runtime, "robot_sim", [] {}, std::chrono::seconds(1),
                                  {{"object", object},
                                   {"world", world},
                                   {"clock", clock},
                                   {"limits", options.limits.to_json()},
                                   {"acceleration_scale", acceleration_scale},
                                   {"base_frame", arm.base_frame_id()}});
  } catch (const pnp::Error& e) {
    log_event("robot_sim", "fatal", {{"error", e.what()}});
    std::fprintf(stderr, "pnp-robot-sim: %s\n", e.what());
    return 2;
  }
}
