// pnp-franka-bridge: a Franka Emika Panda under franka_ros behind
// pnp.robot.v1.RobotControllerService, the service pnp-robot-gateway drives. A ROS 1 node:
// it reads franka_state_controller's FrankaState, the fingers' joint states and a
// tracker's object pose, and streams equilibrium poses to the Cartesian impedance
// controller at --stream-hz within the Panda's Cartesian limits, under the same rules as
// pnp-robot-sim's controller (leases, freshness, the controller's own limits from
// --limits, stops an operator clears). docs/REAL_ROBOT.md has the lab procedure.
//   ROS_MASTER_URI=http://127.0.0.1:11311 pnp-franka-bridge --address 127.0.0.1:50071
//     [--limits deploy/robot/controller.json] [--stream-hz 1000] [topic and frame flags]
//     [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]] [--auth-policy FILE]

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <optional>
#include <thread>
#include <vector>

#include "common/error.h"
#include "common/version.h"
#include "robot/franka_controller.h"
#include "services/common/metrics_registry.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/franka_bridge/ros_franka_link.h"
#include "services/franka_bridge/stand_in_scene_service.h"
#include "services/franka_ros/ros_node.h"
#include "services/robot_controller/robot_controller_service.h"
#include "services/store/remote_audit.h"
#include "services/store/store_flags.h"
#include "sim/panda_hand.h"

namespace {

using namespace pnp::services;

void add_topic_flags(CLI::App& app, FrankaTopics& topics) {
  app.add_option("--state-topic", topics.state, "franka_msgs/FrankaState")->capture_default_str();
  app.add_option("--finger-joints-topic", topics.finger_joints,
                 "sensor_msgs/JointState of the fingers")
      ->capture_default_str();
  app.add_option("--equilibrium-topic", topics.equilibrium_pose,
                 "geometry_msgs/PoseStamped equilibrium of the Cartesian impedance controller")
      ->capture_default_str();
  app.add_option("--object-topic", topics.object_pose,
                 "geometry_msgs/PoseStamped of the object from a tracker, in --base-frame")
      ->capture_default_str();
  app.add_option("--gripper-namespace", topics.gripper, "franka_gripper's actions")
      ->capture_default_str();
  app.add_option("--error-recovery-action", topics.error_recovery,
                 "franka_msgs/ErrorRecovery action (sent only on an operator's Resume)")
      ->capture_default_str();
  app.add_option("--base-frame", topics.base_frame, "the arm's base frame")->capture_default_str();
}

// The bridge's streaming loop: the motion generator ticks and the equilibrium pose goes out
// at a steady rate, whatever the network side does.
void stream(pnp::robot::FrankaController& arm, double rate_hz, const std::stop_token& stop) {
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_hz));
  auto next = Clock::now();
  while (!stop.stop_requested()) {
    next += period;
    std::this_thread::sleep_until(next);
    const auto now = Clock::now();
    if (now - next > 20 * period) next = now;  // descheduled: restart the schedule
    arm.tick(now, 1.0 / rate_hz);
  }
}

}  // namespace

int main(int argc, char** argv) {
  catch_termination_signals();
  init_ros_node(argc, argv, "pnp_franka_bridge");
  CLI::App app{"Franka Emika Panda under franka_ros as a pnp.robot.v1 controller",
               "pnp-franka-bridge"};
  std::string address = "127.0.0.1:50071";
  std::string metrics_address, limits, stand_in_scene;
  double stream_hz = 1000;
  FrankaTopics topics;
  pnp::robot::FrankaBackendOptions backend;
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--limits", limits,
                 "the controller's own limits, JSON (deploy/robot/controller.json; empty: its "
                 "defaults, the same values)");
  app.add_option("--stream-hz", stream_hz, "equilibrium poses per second")
      ->check(CLI::Range(50.0, 2000.0))
      ->capture_default_str();
  app.add_option("--state-timeout-s", backend.state_timeout_s,
                 "no FrankaState for longer stops the arm (a stalled topic)")
      ->capture_default_str();
  app.add_option("--object-timeout-s", backend.object_timeout_s,
                 "a tracker pose older than this is no pose")
      ->capture_default_str();
  add_topic_flags(app, topics);
  app.add_option("--stand-in-scene", stand_in_scene,
                 "pnp-franka-sim's scene service (a loopback host:port): serve "
                 "SimulatedSceneService for gateways driving the stand-in; never with a real arm")
      ->check([](const std::string& a) {
        return a.rfind("127.0.0.1:", 0) == 0 || a.rfind("localhost:", 0) == 0
                   ? std::string()
                   : "expected a loopback host:port (the stand-in's control, never a real arm's)";
      });
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  ServerSecurityFlags security_flags;
  add_server_security_flags(app, security_flags, /*audit_db_flag=*/true);
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
            ? open_remote_audit_trail(store_flags.address, store_flags.tls, "franka_bridge")
            : open_audit_trail(security_flags.audit_db, "franka_bridge");
    security.audit = audit.get();
    if (!ros_master_reachable()) {
      throw pnp::Error(pnp::ErrorCode::kUnavailable,
                       "ROS_MASTER_URI: no ROS master answers (start franka_control first)");
    }
    pnp::robot::ArmControllerOptions controller;
    controller.base_frame_id = topics.base_frame;
    controller.tcp_from_flange_m = pnp::sim::kGripPointFromFlange_m;
    if (!limits.empty()) controller.limits = pnp::robot::ControllerLimits::load(limits);
    backend.tcp_from_flange_m = pnp::sim::kGripPointFromFlange_m;

    // The link is built first and hands messages in once the controller exists.
    std::atomic<pnp::robot::FrankaController*> arm_ready{nullptr};
    FrankaInputs inputs;
    inputs.on_state = [&](const pnp::robot::FrankaStateSample& s) {
      if (auto* arm = arm_ready.load()) arm->on_state(s);
    };
    inputs.on_gripper_width = [&](double w) {
      if (auto* arm = arm_ready.load()) arm->on_gripper_width(w);
    };
    inputs.on_object = [&](const pnp::robot::TrackedObject& o) {
      if (auto* arm = arm_ready.load()) arm->on_object(o);
    };
    inputs.on_refused = [](const std::string& topic, const std::string& why) {
      log_event("franka_bridge", "message_refused", {{"topic", topic}, {"why", why}});
    };
    RosFrankaLink link(topics, inputs);
    pnp::robot::FrankaController arm(link, backend, controller);
    // Destroyed before the controller: no callback reaches it after this.
    const struct CallbackGate {
      RosFrankaLink& link;
      ~CallbackGate() { link.stop_callbacks(); }
    } gate{link};
    arm_ready = &arm;
    std::jthread streamer([&](const std::stop_token& stop) { stream(arm, stream_hz, stop); });

    StreamLimits stream_limits(stream_limit_options(limit_options, idle_timeout_s),
                               "franka_bridge");
    RobotControllerServiceImpl service(arm, &stream_limits);
    std::optional<StandInSceneService> scene;
    std::vector<grpc::Service*> services{&service};
    std::vector<std::string> names{"pnp.robot.v1.RobotControllerService"};
    if (!stand_in_scene.empty()) {
      scene.emplace(arm, stand_in_scene);
      services.push_back(&*scene);
      names.emplace_back("pnp.robot.v1.SimulatedSceneService");
    }
    MetricsRegistry metrics;
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 1 << 20,
                           .services = services,
                           .service_names = names,
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address,
                           .security = security,
                           .log_name = "franka_bridge"});
    const int code =
        serve_until_terminated(runtime, "franka_bridge", [] {}, std::chrono::seconds(1),
                               {{"limits", controller.limits.to_json()},
                                {"stream_hz", stream_hz},
                                {"state_topic", topics.state},
                                {"equilibrium_topic", topics.equilibrium_pose},
                                {"object_topic", topics.object_pose},
                                {"base_frame", topics.base_frame}});
    streamer.request_stop();
    streamer.join();
    link.stop_callbacks();
    shutdown_ros_node();
    return code;
  } catch (const pnp::Error& e) {
    log_event("franka_bridge", "fatal", {{"error", e.what()}});
    std::fprintf(stderr, "pnp-franka-bridge: %s\n", e.what());
    return 2;
  }
}
