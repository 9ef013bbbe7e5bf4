// Integration over real ROS 1: a rosmaster on a free loopback port, pnp-franka-sim (the
// stand-in Franka: franka_ros's topics and actions over the simulated Panda) and
// pnp-franka-bridge (pnp.robot.v1 over franka_ros), driven by a raw gRPC client as the
// gateway drives a controller. This test is itself a ROS node, to inject what only a
// real arm does (a reflex). Built as C++17: it includes ROS's headers.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <std_msgs/String.h>

#include <chrono>
#include <csignal>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "tests/integration/child_process.h"
#include "tests/integration/ros_master.h"

namespace {

namespace rv1 = pnp::robot::v1;
using pnp::integration::ChildProcess;
using pnp::integration::RosMaster;
using pnp::integration::TempDir;
using pnp::integration::wait_until;
using namespace std::chrono_literals;

// The gateway's log events (JSON lines on stderr) named `event`, in order.
std::vector<nlohmann::json> events(const ChildProcess& gateway, const std::string& event) {
  std::vector<nlohmann::json> found;
  std::istringstream lines(gateway.stderr_text());
  for (std::string line; std::getline(lines, line);) {
    const nlohmann::json parsed = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (!parsed.is_object()) continue;
    const auto name = parsed.find("event");
    if (name != parsed.end() && *name == event) found.push_back(parsed);
  }
  return found;
}

template <typename Message>
void publish_once(const std::string& topic, const Message& message) {
  ros::NodeHandle node;
  ros::Publisher pub = node.advertise<Message>(topic, 1, true);
  ASSERT_TRUE(wait_until([&] { return pub.getNumSubscribers() > 0; }, 10s)) << topic;
  pub.publish(message);
  std::this_thread::sleep_for(100ms);  // latched: delivered before the publisher goes
}

class FrankaChain : public ::testing::Test {
 protected:
  void SetUp() override {
    master_.emplace(dir_.path());
    for (const auto& [name, value] : master_->node_env()) setenv(name.c_str(), value.c_str(), 1);
    int argc = 0;
    ros::init(argc, nullptr, "franka_chain_test",
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    ASSERT_TRUE(wait_until([] { return ros::master::check(); }, 30s));
  }

  // With `scene`, the stand-in serves its scene resets and the bridge forwards a gateway's.
  void start_chain(const std::vector<std::string>& sim_flags = {}, bool scene = false) {
    std::vector<std::string> sim{PNP_BIN_DIR "/pnp-franka-sim"};
    sim.insert(sim.end(), sim_flags.begin(), sim_flags.end());
    if (scene) sim.insert(sim.end(), {"--address", "127.0.0.1:0"});
    sim_args_ = sim;
    sim_.emplace("franka_sim", sim, dir_.path(), master_->node_env());
    std::vector<std::string> bridge{PNP_BIN_DIR "/pnp-franka-bridge", "--address", "127.0.0.1:0",
                                    "--limits", PNP_SOURCE_DIR "/deploy/robot/controller.json"};
    if (scene) {
      scene_port_ = sim_->port();
      ASSERT_GT(scene_port_, 0) << sim_->diagnostics();
      bridge.insert(bridge.end(), {"--stand-in-scene", "127.0.0.1:" + std::to_string(scene_port_)});
    }
    bridge_.emplace("franka_bridge", bridge, dir_.path(), master_->node_env());
    const int port = bridge_->port();
    ASSERT_GT(port, 0) << bridge_->diagnostics();
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                                   grpc::InsecureChannelCredentials());
    stub_ = rv1::RobotControllerService::NewStub(channel_);
    // Ready once the bridge has the arm's state: idle, not faulted.
    ASSERT_TRUE(
        wait_until([&] { return state().state().mode() == rv1::CONTROLLER_MODE_IDLE; }, 30s))
        << state().DebugString() << sim_->diagnostics() << bridge_->diagnostics();
  }

  rv1::GetStateResponse state() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 5s);
    rv1::GetStateResponse response;
    stub_->GetState(&context, rv1::GetStateRequest(), &response);
    return response;
  }

  std::string acquire() {
    grpc::ClientContext context;
    rv1::AcquireLeaseRequest request;
    request.set_client_name("franka_chain_test");
    request.mutable_timeout()->set_seconds(10);
    rv1::AcquireLeaseResponse response;
    EXPECT_TRUE(stub_->AcquireLease(&context, request, &response).ok());
    return response.lease_id();
  }

  // A drive stream: open() with the lease, then send() one target per call.
  struct Drive {
    grpc::ClientContext context;
    std::unique_ptr<
        grpc::ClientReaderWriter<rv1::StreamPoseTargetsRequest, rv1::ControllerFeedback>>
        stream;
    std::uint64_t sequence = 0;
    rv1::Quaternion orientation;  // the hand's, held

    Drive(rv1::RobotControllerService::Stub& stub, const std::string& lease,
          const rv1::Quaternion& held)
        : orientation(held) {
      stream = stub.StreamPoseTargets(&context);
      rv1::StreamPoseTargetsRequest open;
      open.set_lease_id(lease);
      stream->Write(open);
    }
    rv1::ControllerFeedback send(double x, double y, double z, double width = 0.08) {
      rv1::StreamPoseTargetsRequest request;
      auto* t = request.mutable_target();
      t->set_sequence(++sequence);
      const auto now = std::chrono::system_clock::now().time_since_epoch();
      t->mutable_stamp()->set_seconds(
          std::chrono::duration_cast<std::chrono::seconds>(now).count());
      t->mutable_stamp()->set_nanos(
          static_cast<int>(std::chrono::duration_cast<std::chrono::nanoseconds>(now % 1s).count()));
      t->set_frame_id("panda_link0");
      t->mutable_pose()->mutable_position()->set_x_m(x);
      t->mutable_pose()->mutable_position()->set_y_m(y);
      t->mutable_pose()->mutable_position()->set_z_m(z);
      *t->mutable_pose()->mutable_orientation() = orientation;
      t->set_gripper_width_m(width);
      stream->Write(request);
      rv1::ControllerFeedback feedback;
      stream->Read(&feedback);
      return feedback;
    }
  };

  // A stand-in killed with SIGKILL comes back as a new process (on the same scene port).
  void restart_stand_in() {
    sim_->kill();
    sim_->wait(10s);
    std::vector<std::string> args = sim_args_;
    if (scene_port_ > 0) args.back() = "127.0.0.1:" + std::to_string(scene_port_);
    sim_.reset();
    sim_.emplace("franka_sim_restarted", args, dir_.path(), master_->node_env());
  }

  // The served policy: the checked-in Panda hierarchy (trained in the paper world).
  int start_inference() {
    const std::string db = dir_.file("pnp.db");
    ChildProcess import(
        "import",
        {PNP_BIN_DIR "/pnp-import", "--db", db, "--hierarchy",
         PNP_SOURCE_DIR "/tests/data/panda_block", "--robot", "panda", "--object", "block"},
        dir_.path());
    EXPECT_TRUE(import.wait(60s).value_or(pnp::integration::ExitStatus{}).ok())
        << import.diagnostics();
    inference_.emplace("inference",
                       std::vector<std::string>{PNP_BIN_DIR "/pnp-inference-server", "--address",
                                                "127.0.0.1:0", "--db", db},
                       dir_.path());
    const int port = inference_->port();
    EXPECT_GT(port, 0) << inference_->diagnostics();
    return port;
  }

  std::vector<std::string> gateway_args(int controller_port, int inference_port, int episodes) {
    return {PNP_BIN_DIR "/pnp-robot-gateway",
            "--controller",
            "127.0.0.1:" + std::to_string(controller_port),
            "--inference",
            "127.0.0.1:" + std::to_string(inference_port),
            "--config",
            PNP_SOURCE_DIR "/deploy/robot/gateway.json",
            "--episodes",
            std::to_string(episodes),
            "--seed",
            "3000",
            "--json"};
  }

  void inject_reflex(const std::string& error) {
    ros::NodeHandle node;
    ros::Publisher pub = node.advertise<std_msgs::String>("/pnp_franka_sim/inject_reflex", 1, true);
    ASSERT_TRUE(wait_until([&] { return pub.getNumSubscribers() > 0; }, 10s));
    std_msgs::String msg;
    msg.data = error;
    pub.publish(msg);
    ASSERT_TRUE(wait_until([&] { return state().stop_kind() == rv1::STOP_KIND_EMERGENCY; }, 10s))
        << state().DebugString();
  }

  TempDir dir_{"franka_chain"};
  std::optional<RosMaster> master_;
  std::optional<ChildProcess> sim_, bridge_, inference_;
  std::vector<std::string> sim_args_;
  int scene_port_ = 0;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<rv1::RobotControllerService::Stub> stub_;
};

TEST_F(FrankaChain, TargetsMoveTheArmAndOnesOutsideTheBridgesBoxAreRefused) {
  start_chain();
  const auto start = state().state().measured().position();
  Drive drive(*stub_, acquire(), state().state().measured().orientation());
  // Below the table: the bridge's own box refuses it, nothing moves.
  EXPECT_EQ(drive.send(start.x_m(), start.y_m(), -0.05).status(),
            rv1::CONTROLLER_STATUS_OUTSIDE_LIMITS);
  // Down 3 cm in three steps, at the policy's 25 Hz: the arm follows.
  rv1::ControllerFeedback last;
  for (int k = 1; k <= 3; ++k) {
    last = drive.send(start.x_m(), start.y_m(), start.z_m() - 0.01 * k);
    EXPECT_EQ(last.status(), rv1::CONTROLLER_STATUS_OK) << last.DebugString();
    std::this_thread::sleep_for(40ms);
  }
  ASSERT_TRUE(wait_until(
      [&] {
        return std::abs(state().state().measured().position().z_m() - (start.z_m() - 0.03)) < 0.003;
      },
      5s))
      << state().DebugString();
  EXPECT_NEAR(state().state().measured().position().x_m(), start.x_m(), 0.003);
}

TEST_F(FrankaChain, AReflexHoldsTheArmUntilAnOperatorAcknowledgesIt) {
  start_chain();
  const auto start = state().state().measured().position();
  const std::string lease = acquire();
  Drive drive(*stub_, lease, state().state().measured().orientation());
  ASSERT_EQ(drive.send(start.x_m(), start.y_m(), start.z_m() - 0.01).status(),
            rv1::CONTROLLER_STATUS_OK);
  inject_reflex("cartesian_reflex");
  const rv1::GetStateResponse stopped = state();
  EXPECT_EQ(stopped.state().mode(), rv1::CONTROLLER_MODE_STOPPED);
  EXPECT_NE(stopped.stop_reason().find("cartesian_reflex"), std::string::npos)
      << stopped.stop_reason();
  EXPECT_EQ(drive.send(start.x_m(), start.y_m(), start.z_m() - 0.02).status(),
            rv1::CONTROLLER_STATUS_STOPPED);
  {  // The lease holder alone cannot clear it.
    grpc::ClientContext context;
    rv1::ResumeRequest request;
    request.set_lease_id(lease);
    rv1::ResumeResponse response;
    EXPECT_FALSE(stub_->Resume(&context, request, &response).ok());
  }
  {  // An operator repeating the reason does: error recovery goes to franka_control.
    grpc::ClientContext context;
    rv1::ResumeRequest request;
    request.set_operator_name("operator");
    request.set_acknowledged_reason(stopped.stop_reason());
    rv1::ResumeResponse response;
    const grpc::Status status = stub_->Resume(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
  }
  ASSERT_TRUE(wait_until(
      [&] {
        return drive.send(start.x_m(), start.y_m(), start.z_m() - 0.02).status() ==
               rv1::CONTROLLER_STATUS_OK;
      },
      10s, 50ms))
      << state().DebugString();
}

TEST_F(FrankaChain, AKilledStandInStopsTheArmWithinTheStateTimeout) {
  start_chain();
  Drive drive(*stub_, acquire(), state().state().measured().orientation());
  sim_->kill();
  ASSERT_TRUE(wait_until([&] { return state().stop_kind() == rv1::STOP_KIND_EMERGENCY; }, 2s));
  const auto s = state();
  EXPECT_NE(s.stop_reason().find("stalled"), std::string::npos) << s.stop_reason();
  EXPECT_EQ(drive.send(0.4, 0.0, 0.2).status(), rv1::CONTROLLER_STATUS_STOPPED);
}

TEST_F(FrankaChain, WithoutATrackerTheBridgeReportsNoObject) {
  start_chain({"--tracker-hz", "0"});
  EXPECT_FALSE(state().state().has_object());
}

TEST_F(FrankaChain, TheTrackersObjectIsReported) {
  start_chain();
  ASSERT_TRUE(wait_until([&] { return state().state().has_object(); }, 5s));
  EXPECT_NEAR(state().state().object().pose().position().z_m(), 0.02, 0.02);
}

// The served hierarchy (the checked-in Panda one, trained in the paper world) through
// pnp-robot-gateway, on the same scenes: through the bridge to the stand-in Franka, and
// on pnp-robot-sim in real time. Both chains run the simulated Panda on the wall clock,
// so their episodes differ by timing; the bridge must not cost more than two episodes.
TEST_F(FrankaChain, TheGatewayDrivesTheBridgeAsItDrivesTheSimulatedController) {
  start_chain(std::vector<std::string>{"--world", "paper"}, /*scene=*/true);
  const int inference_port = start_inference();
  ChildProcess robot_sim(
      "robot_sim",
      {PNP_BIN_DIR "/pnp-robot-sim", "--address", "127.0.0.1:0", "--clock", "realtime", "--world",
       "paper", "--limits", PNP_SOURCE_DIR "/deploy/robot/controller.json"},
      dir_.path());
  const auto drive = [&](const std::string& name, int controller_port) {
    ChildProcess gateway(name, gateway_args(controller_port, inference_port, 20), dir_.path());
    const auto status = gateway.wait(300s);
    EXPECT_TRUE(status && status->ok()) << gateway.diagnostics();
    return nlohmann::json::parse(gateway.stdout_text());
  };
  const nlohmann::json bridge = drive("gateway_bridge", bridge_->port());
  const nlohmann::json direct = drive("gateway_robot_sim", robot_sim.port());
  EXPECT_EQ(bridge["episodes"], 20);
  EXPECT_EQ(bridge["refused_targets"], 0) << bridge.dump();
  EXPECT_EQ(bridge["missed_periods"], 0) << bridge.dump();
  EXPECT_GE(bridge["successes"].get<int>(), direct["successes"].get<int>() - 2)
      << "through the bridge " << bridge["successes"] << ", on pnp-robot-sim "
      << direct["successes"];
  EXPECT_GE(bridge["successes"].get<int>(), 16) << bridge.dump();
}

// A dry run on a real arm's terms (no scene reset: the goal given, the object where the
// tracker sees it): the shadow plays from the arm's measured state, the record holds the
// targets it would have sent, and the arm itself does not move.
TEST_F(FrankaChain, ADryRunThroughTheBridgeRecordsTheMotionAndTheArmHolds) {
  start_chain(std::vector<std::string>{"--world", "paper"});
  const int inference_port = start_inference();
  ASSERT_TRUE(wait_until([&] { return state().state().has_object(); }, 5s));
  const auto before = state().state().measured().position();
  const std::string record = dir_.file("record.jsonl");
  std::vector<std::string> args = gateway_args(bridge_->port(), inference_port, 1);
  args.insert(args.end(), {"--goal", "0.45,0.1,0.15", "--dry-run", "--controller-limits",
                           PNP_SOURCE_DIR "/deploy/robot/controller.json", "--record", record,
                           "--view", dir_.file("views")});
  ChildProcess gateway("gateway_dry_run", args, dir_.path());
  const auto status = gateway.wait(120s);
  ASSERT_TRUE(status && status->ok()) << gateway.diagnostics();
  const nlohmann::json summary = nlohmann::json::parse(gateway.stdout_text());
  EXPECT_EQ(summary["arm_left"]["untouched (dry run)"], 1) << summary.dump();
  std::istringstream lines(pnp::integration::read_file(record));
  int targets = 0;
  for (std::string line; std::getline(lines, line); ++targets) {
    const nlohmann::json target = nlohmann::json::parse(line);
    EXPECT_EQ(target["position_base_m"].size(), 3u) << line;
  }
  EXPECT_GT(targets, 5);
  // The operator's picture of it: the shadow's path, drawn as the dashboard draws episodes.
  const std::string view = pnp::integration::read_file(dir_.path() / "views" / "episode_3000.svg");
  EXPECT_NE(view.find("class=\"episode\""), std::string::npos) << view.substr(0, 200);
  EXPECT_NE(view.find("dry run"), std::string::npos);
  const auto after = state().state().measured().position();
  EXPECT_NEAR(after.x_m(), before.x_m(), 0.002);
  EXPECT_NEAR(after.y_m(), before.y_m(), 0.002);
  EXPECT_NEAR(after.z_m(), before.z_m(), 0.002);
}

// Every fault a real arm meets, each in its own episode of one gateway run through the
// bridge (--await-operator): each ends that episode with the arm held, and the run goes
// on to its last episode. The test is the operator: it clears each emergency stop by
// repeating its reason, as `pnpctl robot resume --ack REASON` does.
TEST_F(FrankaChain, EachFaultEndsItsEpisodeHeldAndTheRunGoesOn) {
  start_chain(std::vector<std::string>{"--world", "paper"}, /*scene=*/true);
  const int inference_port = start_inference();
  constexpr int kEpisodes = 10;
  constexpr double kMaxStall_s = 60;  // the stand-in's longest
  std::vector<std::string> args = gateway_args(bridge_->port(), inference_port, kEpisodes);
  args.insert(args.end(), {"--await-operator", "60"});
  ChildProcess gateway("gateway_faults", args, dir_.path());

  // Waits for an episode after `after` to be under way (still running 0.4 s after its
  // start: the arm is on its way), then `fault`; returns the seed it hit.
  const auto ended = [&](std::uint64_t seed) {
    for (const auto& e : events(gateway, "episode_end"))
      if (e["seed"] == seed) return true;
    return false;
  };
  std::uint64_t after = 0;
  const auto during_next_episode = [&](const std::function<void()>& fault) {
    std::uint64_t seed = 0;
    EXPECT_TRUE(wait_until(
        [&] {
          const auto starts = events(gateway, "episode_start");
          if (starts.empty() || starts.back()["seed"].get<std::uint64_t>() <= after) return false;
          seed = starts.back()["seed"].get<std::uint64_t>();
          std::this_thread::sleep_for(400ms);
          return !ended(seed);
        },
        60s))
        << gateway.diagnostics();
    fault();
    after = seed;
    return seed;
  };
  // The episode `seed` ended as `end` with the arm left `arm_left`, its reason naming `why`.
  const auto expect_ended = [&](std::uint64_t seed, const std::string& end,
                                const std::string& arm_left, const std::string& why) {
    nlohmann::json report;
    ASSERT_TRUE(wait_until(
        [&] {
          for (const auto& e : events(gateway, "episode_end"))
            if (e["seed"] == seed) report = e;
          return !report.is_null();
        },
        60s))
        << gateway.diagnostics();
    if (end.empty()) {  // played to its end
      EXPECT_TRUE(report["end"] == "success" || report["end"] == "step_cap") << report.dump();
    } else {
      EXPECT_EQ(report["end"], end) << report.dump();
    }
    EXPECT_EQ(report["arm_left"], arm_left) << report.dump();
    EXPECT_NE(report["reason"].get<std::string>().find(why), std::string::npos) << report.dump();
    after = std::max(after, seed);
  };
  // The operator clears the emergency stop once the gateway waits for it (retried while a
  // restarted arm's error recovery is not yet served).
  std::size_t cleared = 0;
  const auto operator_clears = [&] {
    ASSERT_TRUE(
        wait_until([&] { return events(gateway, "awaiting_operator").size() > cleared; }, 60s))
        << gateway.diagnostics();
    ASSERT_TRUE(wait_until(
        [&] {
          const rv1::GetStateResponse now = state();
          if (now.stop_kind() != rv1::STOP_KIND_EMERGENCY) return true;
          grpc::ClientContext context;
          rv1::ResumeRequest request;
          request.set_operator_name("operator");
          request.set_acknowledged_reason(now.stop_reason());
          rv1::ResumeResponse response;
          stub_->Resume(&context, request, &response);
          return false;
        },
        60s, 500ms))
        << state().DebugString() << bridge_->diagnostics();
    ASSERT_TRUE(
        wait_until([&] { return events(gateway, "operator_cleared").size() > cleared; }, 10s))
        << gateway.diagnostics();
    ++cleared;
  };

  const std::uint64_t reflex = during_next_episode([&] {
    std_msgs::String error;
    error.data = "cartesian_reflex";
    publish_once("/pnp_franka_sim/inject_reflex", error);
  });
  expect_ended(reflex, "stopped", "emergency_stop", "cartesian_reflex");
  operator_clears();

  const std::uint64_t stalled = during_next_episode([&] {
    std_msgs::Float64 seconds;
    seconds.data = 1.0;
    publish_once("/pnp_franka_sim/stall_state", seconds);
  });
  expect_ended(stalled, "stopped", "emergency_stop", "stalled");
  std::this_thread::sleep_for(1s);  // the state flows again
  operator_clears();

  const std::uint64_t killed = during_next_episode([&] { restart_stand_in(); });
  expect_ended(killed, "stopped", "emergency_stop", "stalled");
  operator_clears();

  const std::uint64_t stopped = during_next_episode([&] {
    grpc::ClientContext context;
    rv1::StopRequest request;
    request.set_reason("a person stepped into the cell");
    request.set_kind(rv1::STOP_KIND_EMERGENCY);
    rv1::StopResponse response;
    EXPECT_TRUE(stub_->Stop(&context, request, &response).ok());
  });
  expect_ended(stopped, "stopped", "emergency_stop", "a person stepped into the cell");
  operator_clears();

  // After every emergency stop, the next episode plays to its end.
  expect_ended(stopped + 1, "", "tracking", "");

  // Last, a tracker that goes silent: the object's pose goes stale mid-episode, and is
  // missing at each later episode's start, which ends before the arm moves. Each ends
  // with a protective stop (the next episode clears it as the lease holder), and the run
  // goes on to its last episode.
  std_msgs::Float64 seconds;
  seconds.data = kMaxStall_s;
  const std::uint64_t stale =
      during_next_episode([&] { publish_once("/pnp_franka_sim/stall_tracker", seconds); });
  expect_ended(stale, "controller_fault", "protective_stop", "object");
  for (std::uint64_t seed = stale + 1; seed < 3000 + kEpisodes; ++seed) {
    expect_ended(seed, "controller_fault", "protective_stop", "at the start");
  }
  for (const auto& e : events(gateway, "episode_end")) {
    if (e["seed"] > stale) {
      EXPECT_EQ(e["steps"], 0) << e.dump();
    }
  }

  const auto status = gateway.wait(300s);
  ASSERT_TRUE(status && status->ok()) << gateway.diagnostics();
  const nlohmann::json summary = nlohmann::json::parse(gateway.stdout_text());
  EXPECT_EQ(summary["episodes"], kEpisodes) << summary.dump();
  EXPECT_EQ(summary["seeds"].back(), 3000 + kEpisodes - 1) << summary.dump();
}

}  // namespace
