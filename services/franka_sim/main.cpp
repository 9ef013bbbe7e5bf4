// pnp-franka-sim: a stand-in Franka on real ROS 1. The simulated Panda of core/arm_sim
// behaves as franka_control with the Cartesian impedance controller, franka_gripper and
// a tracker would (arm_sim::FrankaStandIn), on the wall clock, so pnp-franka-bridge's
// whole chain (gateway -> bridge -> ROS -> arm) runs without hardware. Its tests start a
// rosmaster on a free loopback port and point ROS_MASTER_URI at it.
//   ROS_MASTER_URI=http://127.0.0.1:11311 pnp-franka-sim [--object block] [--seed 0]
//     [--state-hz 100] [--tracker-hz 30] [--control /pnp_franka_sim]

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <thread>

#include "arm_sim/franka_stand_in.h"
#include "common/error.h"
#include "common/version.h"
#include "services/common/server_runtime.h"
#include "services/franka_ros/ros_node.h"
#include "services/franka_sim/franka_sim_scene_service.h"
#include "services/franka_sim/ros_franka_sim_link.h"

namespace {

using namespace pnp::services;
using Clock = std::chrono::steady_clock;

std::array<double, 16> column_major(const Eigen::Matrix4d& m) {
  std::array<double, 16> out{};
  Eigen::Map<Eigen::Matrix4d>(out.data()) = m;
  return out;
}

FrankaSimReport report_of(const pnp::arm_sim::FrankaStandInState& s) {
  FrankaSimReport r;
  r.time_s = s.time_s;
  r.O_T_EE = column_major(s.base_from_ee);
  r.O_T_EE_d = column_major(s.base_from_ee_desired);
  r.F_T_EE = column_major(s.flange_from_ee);
  r.q = s.q;
  r.dq = s.dq;
  r.tau_J = s.tau;
  r.robot_mode = s.robot_mode;
  r.current_errors = s.current_errors;
  r.finger_gap_m = s.finger_gap_m;
  r.object_base = s.object_base;
  return r;
}

// A topic a test silenced until a steady-clock time (std::atomic: set from ROS's threads).
class Silence {
 public:
  void for_seconds(double s) {
    until_.store(
        Clock::now().time_since_epoch().count() +
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)).count());
  }
  bool now() const { return Clock::now().time_since_epoch().count() < until_.load(); }

 private:
  std::atomic<Clock::rep> until_{0};
};

// Runs `work` every `period` on the steady clock until stopped (descheduled: it catches
// up at most 20 periods, then restarts the schedule).
template <typename Work>
void every(Clock::duration period, const std::stop_token& stop, Work&& work) {
  auto next = Clock::now();
  while (!stop.stop_requested()) {
    next += period;
    std::this_thread::sleep_until(next);
    if (Clock::now() - next > 20 * period) next = Clock::now();
    work();
  }
}

Clock::duration period_of(double hz) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / hz));
}

}  // namespace

int main(int argc, char** argv) {
  catch_termination_signals();
  init_ros_node(argc, argv, "pnp_franka_sim");
  CLI::App app{
      "A stand-in Franka on ROS 1: franka_ros's topics and actions over the simulated "
      "Panda",
      "pnp-franka-sim"};
  std::string object = "block";
  std::string address;
  std::string world(pnp::sim::world_profile_name(pnp::sim::kDefaultWorldProfile));
  std::uint64_t seed = 0;
  double state_hz = 100, tracker_hz = 30;
  FrankaSimTopics topics;
  pnp::arm_sim::FrankaStandInOptions options;
  app.add_option("--object", object, "block, cylinder or small_block")->capture_default_str();
  app.add_option("--world", world, "world profile: paper or gym")->capture_default_str();
  app.add_option("--seed", seed, "the first scene's episode seed")->capture_default_str();
  app.add_option("--state-hz", state_hz,
                 "FrankaState and joint states per second (franka_state_controller's "
                 "publish_rate)")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--tracker-hz", tracker_hz, "object poses per second (0: no tracker)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  app.add_option("--reflex-deviation-m", options.reflex_deviation_m,
                 "an equilibrium further than this from the end effector is a cartesian_reflex")
      ->capture_default_str();
  app.add_option("--address", address,
                 "host:port (loopback) for SimulatedSceneService, the stand-in's scene resets "
                 "(port 0: any free port, printed first on stdout; empty: none)");
  app.add_option("--control", topics.control, "namespace of the test controls")
      ->capture_default_str();
  app.add_option("--base-frame", topics.base_frame, "the arm's base frame")->capture_default_str();
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  try {
    options.object = pnp::sim::parse_object(object, "--object");
    options.world = pnp::sim::parse_world_profile(world, "--world");
    if (!ros_master_reachable()) {
      throw pnp::Error(pnp::ErrorCode::kUnavailable, "ROS_MASTER_URI: no ROS master answers");
    }
    std::mutex mutex;
    pnp::arm_sim::FrankaStandIn arm(options);
    arm.reset(seed);
    const auto locked = [&](auto&& f) {
      std::lock_guard lock(mutex);
      return f();
    };
    FrankaSimInputs inputs;
    inputs.on_equilibrium = [&](const pnp::geometry::Pose& ee,
                                std::chrono::system_clock::time_point stamp) {
      locked([&] { arm.set_equilibrium(ee, stamp); });
    };
    inputs.on_move = [&](double w) { return locked([&] { return arm.gripper_move(w); }); };
    inputs.on_grasp = [&](double w) { return locked([&] { return arm.gripper_grasp(w); }); };
    inputs.on_error_recovery = [&] { return locked([&] { return arm.error_recovery(); }); };
    inputs.on_inject_reflex = [&](const std::string& e) {
      locked([&] { arm.inject_reflex(e); });
      log_event("franka_sim", "reflex_injected", {{"error", e}});
    };
    inputs.on_reset_scene = [&](std::uint64_t s) {
      locked([&] { arm.reset(s); });
      log_event("franka_sim", "scene_reset", {{"seed", s}});
    };
    Silence state_silence, tracker_silence;
    inputs.on_stall_state = [&](double s) {
      state_silence.for_seconds(s);
      log_event("franka_sim", "state_stalled", {{"seconds", s}});
    };
    inputs.on_stall_tracker = [&](double s) {
      tracker_silence.for_seconds(s);
      log_event("franka_sim", "tracker_stalled", {{"seconds", s}});
    };
    RosFrankaSimLink link(topics, inputs);
    std::jthread physics([&](const std::stop_token& stop) {
      every(std::chrono::milliseconds(1), stop, [&] { locked([&] { arm.advance(0.001); }); });
    });
    std::jthread state([&](const std::stop_token& stop) {
      every(period_of(state_hz), stop, [&] {
        if (state_silence.now()) return;
        const auto s = locked([&] { return arm.state(); });
        link.publish_state(report_of(s));
        link.publish_fingers(s.finger_gap_m);
      });
    });
    std::jthread tracker([&](const std::stop_token& stop) {
      if (tracker_hz <= 0) return;
      every(period_of(tracker_hz), stop, [&] {
        if (!tracker_silence.now())
          link.publish_object(locked([&] { return arm.state().object_base; }));
      });
    });
    const nlohmann::json fields{
        {"object", object}, {"seed", seed}, {"state_hz", state_hz}, {"tracker_hz", tracker_hz}};
    if (address.empty()) {
      log_event("franka_sim", "ready", fields);
      wait_for_termination_signal();
    } else {
      FrankaSimSceneService scene(arm, mutex, topics.base_frame);
      ServerRuntime runtime({.address = address,
                             .max_message_bytes = 1 << 16,
                             .services = {&scene},
                             .service_names = {"pnp.robot.v1.SimulatedSceneService"},
                             .metrics = nullptr,
                             .metrics_address = {},
                             .security = {},
                             .log_name = "franka_sim"});
      serve_until_terminated(
          runtime, "franka_sim", [] {}, std::chrono::seconds(1), fields);
    }
    link.stop_callbacks();
    shutdown_ros_node();
    return 0;
  } catch (const pnp::Error& e) {
    log_event("franka_sim", "fatal", {{"error", e.what()}});
    std::fprintf(stderr, "pnp-franka-sim: %s\n", e.what());
    return 2;
  }
}
