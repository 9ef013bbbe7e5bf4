// Integration over real ROS 1: a rosmaster on a free loopback port, pnp-franka-sim (the
// stand-in Franka: franka_ros's topics and actions over the simulated Panda) and
// pnp-franka-bridge (pnp.robot.v1 over franka_ros), driven by a raw gRPC client as the
// gateway drives a controller. This test is itself a ROS node, to inject what only a
// real arm does (a reflex). Built as C++17: it includes ROS's headers.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/String.h>

#include <chrono>
#include <csignal>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>

#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "tests/integration/child_process.h"

namespace {

namespace rv1 = pnp::robot::v1;
using pnp::integration::ChildProcess;
using pnp::integration::read_file;
using pnp::integration::TempDir;
using pnp::integration::wait_until;
using namespace std::chrono_literals;

// Nodes advertise loopback addresses only, and log under the test's directory.
std::vector<std::pair<std::string, std::string>> ros_env(const TempDir& dir,
                                                         const std::string& master_uri) {
  return {{"ROS_MASTER_URI", master_uri},
          {"ROS_IP", "127.0.0.1"},
          {"ROS_HOSTNAME", "127.0.0.1"},
          {"ROS_HOME", dir.path().string()},
          {"ROS_LOG_DIR", (dir.path() / "ros_log").string()}};
}

class FrankaChain : public ::testing::Test {
 protected:
  void SetUp() override {
    master_.emplace("rosmaster",
                    std::vector<std::string>{"/usr/bin/rosmaster", "--core", "-p", "0"},
                    dir_.path(), ros_env(dir_, "http://127.0.0.1:0/"));
    // rosmaster on port 0 names the port it took in its log.
    const std::regex uri(R"(uri\[(http://127\.0\.0\.1:[0-9]+/)\])");
    ASSERT_TRUE(wait_until(
        [&] {
          const std::string log = read_file(dir_.path() / "ros_log" / "master.log");
          std::smatch match;
          if (!std::regex_search(log, match, uri)) return false;
          master_uri_ = match[1];
          return true;
        },
        30s))
        << master_->diagnostics();
    for (const auto& [name, value] : ros_env(dir_, master_uri_))
      setenv(name.c_str(), value.c_str(), 1);
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
    sim_.emplace("franka_sim", sim, dir_.path(), ros_env(dir_, master_uri_));
    std::vector<std::string> bridge{PNP_BIN_DIR "/pnp-franka-bridge", "--address", "127.0.0.1:0",
                                    "--limits", PNP_SOURCE_DIR "/deploy/robot/controller.json"};
    if (scene) {
      const int scene_port = sim_->port();
      ASSERT_GT(scene_port, 0) << sim_->diagnostics();
      bridge.insert(bridge.end(), {"--stand-in-scene", "127.0.0.1:" + std::to_string(scene_port)});
    }
    bridge_.emplace("franka_bridge", bridge, dir_.path(), ros_env(dir_, master_uri_));
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
  std::string master_uri_;
  std::optional<ChildProcess> master_, sim_, bridge_;
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
  const std::string db = dir_.file("pnp.db");
  ChildProcess import(
      "import",
      {PNP_BIN_DIR "/pnp-import", "--db", db, "--hierarchy",
       PNP_SOURCE_DIR "/tests/data/panda_block", "--robot", "panda", "--object", "block"},
      dir_.path());
  ASSERT_TRUE(import.wait(60s).value_or(pnp::integration::ExitStatus{}).ok())
      << import.diagnostics();
  ChildProcess inference(
      "inference", {PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db", db},
      dir_.path());
  ChildProcess robot_sim(
      "robot_sim",
      {PNP_BIN_DIR "/pnp-robot-sim", "--address", "127.0.0.1:0", "--clock", "realtime", "--world",
       "paper", "--limits", PNP_SOURCE_DIR "/deploy/robot/controller.json"},
      dir_.path());
  const int inference_port = inference.port();
  ASSERT_GT(inference_port, 0) << inference.diagnostics();
  const auto drive = [&](const std::string& name, int controller_port) {
    ChildProcess gateway(name,
                         {PNP_BIN_DIR "/pnp-robot-gateway", "--controller",
                          "127.0.0.1:" + std::to_string(controller_port), "--inference",
                          "127.0.0.1:" + std::to_string(inference_port), "--config",
                          PNP_SOURCE_DIR "/deploy/robot/gateway.json", "--episodes", "20", "--seed",
                          "3000", "--json"},
                         dir_.path());
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

}  // namespace
