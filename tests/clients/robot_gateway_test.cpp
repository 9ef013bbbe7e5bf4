// The robot gateway end to end, in process over loopback with real stubs: the controller
// stand-in (lockstep, so episodes run at computer speed with the same physics), the
// inference service serving the checked-in Panda hierarchy, and the gateway's episode
// loop between them.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <thread>
#include <tuple>

#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "common/error.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/robot_controller_service.h"
#include "support/checked_in_hierarchy.h"

namespace pnp::gateway {
namespace {

namespace rv1 = robot::v1;
namespace pv1 = policy::v1;

EpisodeOptions episode(std::uint64_t seed, bool dry_run = false) {
  EpisodeOptions options;
  options.seed = seed;
  options.dry_run = dry_run;
  return options;
}

arm_sim::StandInOptions lockstep() {
  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kLockstep;
  options.world = sim::WorldProfile::kPaper;  // the checked-in hierarchy's world
  return options;
}

std::string loopback(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

robot::GatewayConfig panda_config() {
  return robot::GatewayConfig::load(std::filesystem::path(PNP_SOURCE_DIR) / "deploy" / "robot" /
                                    "gateway.json");
}

// A policy service whose sessions answer too late: the gateway's dead-man must trip.
class StalledPolicyService final : public pv1::PolicyService::Service {
 public:
  grpc::Status GetServingStatus(grpc::ServerContext*, const pv1::GetServingStatusRequest*,
                                pv1::GetServingStatusResponse* response) override {
    response->add_roles()->set_world(common::v1::WORLD_GYM);
    response->set_ready(true);
    return grpc::Status::OK;
  }
  grpc::Status PredictSession(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<pv1::PredictSessionResponse, pv1::PredictSessionRequest>* stream)
      override {
    pv1::PredictSessionRequest request;
    while (stream->Read(&request)) {
      for (int k = 0; k < 50 && !context->IsCancelled(); ++k) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      if (context->IsCancelled()) break;
      stream->Write({});
    }
    return grpc::Status::OK;
  }
};

// A controller whose readings are broken (a finger gap far below zero): the gateway must
// end that episode with the reason, send nothing, and stay up.
class BrokenReadingController final : public rv1::RobotControllerService::Service,
                                      public rv1::SimulatedSceneService::Service {
 public:
  grpc::Status AcquireLease(grpc::ServerContext*, const rv1::AcquireLeaseRequest*,
                            rv1::AcquireLeaseResponse* response) override {
    response->set_lease_id("lease");
    return grpc::Status::OK;
  }
  grpc::Status ReleaseLease(grpc::ServerContext*, const rv1::ReleaseLeaseRequest*,
                            rv1::ReleaseLeaseResponse*) override {
    return grpc::Status::OK;
  }
  grpc::Status ResetScene(grpc::ServerContext*, const rv1::ResetSceneRequest*,
                          rv1::ResetSceneResponse* response) override {
    fill(*response->mutable_state());
    response->mutable_goal()->set_x_m(0.5);
    return grpc::Status::OK;
  }
  grpc::Status GetState(grpc::ServerContext*, const rv1::GetStateRequest*,
                        rv1::GetStateResponse* response) override {
    fill(*response->mutable_state());
    response->set_lockstep(true);
    return grpc::Status::OK;
  }
  grpc::Status StreamPoseTargets(
      grpc::ServerContext*,
      grpc::ServerReaderWriter<rv1::ControllerFeedback, rv1::StreamPoseTargetsRequest>* stream)
      override {
    rv1::StreamPoseTargetsRequest request;
    while (stream->Read(&request)) {
      if (request.has_target()) ++targets;
    }
    return grpc::Status::OK;
  }
  std::atomic<int> targets{0};

 private:
  static void fill(rv1::ControllerFeedback& state) {
    state.set_frame_id("panda_link0");
    state.mutable_measured()->mutable_position()->set_x_m(0.46);
    state.mutable_measured()->mutable_position()->set_z_m(0.2);
    state.mutable_measured()->mutable_orientation()->set_x(1);  // gripper down
    *state.mutable_commanded() = state.measured();
    state.mutable_object()->mutable_pose()->mutable_position()->set_x_m(0.3);
    state.mutable_object()->mutable_pose()->mutable_orientation()->set_w(1);
    state.set_gripper_width_m(-0.05);  // 5 cm below closed: not a finger gap
    state.set_mode(rv1::CONTROLLER_MODE_IDLE);
  }
};

class GatewayEndToEnd : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("pnp_gateway_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    const std::string db = (dir_ / "pnp.db").string();
    {
      store::RunStore store(db);
      testing::promote_checked_in_panda_hierarchy(store);
    }
    arm_ = std::make_unique<arm_sim::ControllerStandIn>(lockstep());
    controller_service_ = std::make_unique<services::RobotControllerServiceImpl>(*arm_);
    scene_service_ = std::make_unique<services::SimulatedSceneServiceImpl>(*arm_);
    controller_server_ = std::make_unique<services::ServerRuntime>(services::ServerConfig{
        "127.0.0.1:0", 1 << 20, {controller_service_.get(), scene_service_.get()}, {}});
    policy_service_ = std::make_unique<services::PolicyServiceImpl>(db);
    policy_server_ = std::make_unique<services::ServerRuntime>(
        services::ServerConfig{"127.0.0.1:0", 4 << 20, {policy_service_.get()}, {}});
    controller_ = std::make_unique<ControllerLink>(
        grpc::CreateChannel(loopback(controller_server_->port()),
                            grpc::InsecureChannelCredentials()),
        loopback(controller_server_->port()), std::chrono::milliseconds(5000));
    policy_stub_ = pv1::PolicyService::NewStub(
        grpc::CreateChannel(loopback(policy_server_->port()), grpc::InsecureChannelCredentials()));
  }
  void TearDown() override {
    controller_.reset();
    policy_server_->shutdown(std::chrono::milliseconds(500));
    controller_server_->shutdown(std::chrono::milliseconds(500));
    std::filesystem::remove_all(dir_);
  }

  EventLog recorder() {
    return [this](std::string_view event, const nlohmann::json& fields) {
      events_.push_back({std::string(event), fields});
    };
  }
  int count(std::string_view event) const {
    int n = 0;
    for (const auto& [e, fields] : events_) n += e == event ? 1 : 0;
    return n;
  }

  std::filesystem::path dir_;
  std::unique_ptr<arm_sim::ControllerStandIn> arm_;
  std::unique_ptr<services::RobotControllerServiceImpl> controller_service_;
  std::unique_ptr<services::SimulatedSceneServiceImpl> scene_service_;
  std::unique_ptr<services::ServerRuntime> controller_server_;
  std::unique_ptr<services::PolicyServiceImpl> policy_service_;
  std::unique_ptr<services::ServerRuntime> policy_server_;
  std::unique_ptr<ControllerLink> controller_;
  std::unique_ptr<pv1::PolicyService::Stub> policy_stub_;
  std::vector<std::pair<std::string, nlohmann::json>> events_;
  std::atomic<bool> not_interrupted_{false};
};

// The acceptance case: the served policy picks and places through the gateway and the
// simulated controller. Lockstep physics and greedy inference make it deterministic.
TEST_F(GatewayEndToEnd, PicksAndPlacesThroughTheControllerStandIn) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  std::vector<EpisodeReport> reports;
  for (std::uint64_t seed = 900; seed < 910; ++seed) {
    reports.push_back(runner.run(episode(seed), not_interrupted_));
  }
  const nlohmann::json summary = summarize(reports);
  EXPECT_GE(summary["successes"].get<int>(), 8) << summary.dump(2);
  for (const EpisodeReport& r : reports) {
    ::testing::Test::RecordProperty("seed_" + std::to_string(r.seed),
                                    std::string(episode_end_name(r.end)));
    EXPECT_TRUE(r.end == EpisodeEnd::kSuccess || r.end == EpisodeEnd::kStepCap)
        << "seed " << r.seed << ": " << episode_end_name(r.end) << " " << r.reason;
    EXPECT_EQ(r.controller_refused, 0) << "seed " << r.seed;
    EXPECT_EQ(r.steps, static_cast<int>(r.cycle_us.size()));
    EXPECT_LE(r.steps, config.max_episode_steps);
  }
}

TEST_F(GatewayEndToEnd, DryRunSendsNothing) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  const EpisodeReport report = runner.run(episode(901, true), not_interrupted_);
  EXPECT_EQ(report.end, EpisodeEnd::kStepCap);
  EXPECT_FALSE(report.success);
  EXPECT_EQ(count("target"), config.max_episode_steps);
  EXPECT_EQ(arm_->state().sequence, 0u);  // no target ever reached the controller
}

TEST_F(GatewayEndToEnd, InterruptStopsTheArmFirst) {
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  std::atomic<bool> interrupted{true};
  const EpisodeReport report = runner.run(episode(902), interrupted);
  EXPECT_EQ(report.end, EpisodeEnd::kInterrupted);
  EXPECT_EQ(arm_->state().arm.mode, arm_sim::ArmMode::kStopped);
}

TEST_F(GatewayEndToEnd, StalledInferenceHoldsTheArmAndEndsTheEpisode) {
  StalledPolicyService stalled;
  services::ServerRuntime stalled_server({"127.0.0.1:0", 1 << 20, {&stalled}, {}});
  auto stub = pv1::PolicyService::NewStub(
      grpc::CreateChannel(loopback(stalled_server.port()), grpc::InsecureChannelCredentials()));
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *controller_, *stub, recorder());
  const auto before = arm_->state();
  const EpisodeReport report = runner.run(episode(903), not_interrupted_);
  EXPECT_EQ(report.end, EpisodeEnd::kDeadman);
  EXPECT_NE(report.reason.find("inference did not answer"), std::string::npos) << report.reason;
  EXPECT_EQ(report.steps, 0);
  // The one target sent was the hold: the commanded pose did not move.
  const auto after = arm_->state();
  EXPECT_EQ(after.sequence, 1u);
  EXPECT_LT((after.arm.commanded_base.position_m - before.arm.commanded_base.position_m).norm(),
            1e-9);
  EXPECT_EQ(count("deadman"), 1);
  stalled_server.shutdown(std::chrono::milliseconds(100));
}

// A policy service that answers but serves nothing yet.
class UnreadyPolicyService final : public pv1::PolicyService::Service {
 public:
  grpc::Status GetServingStatus(grpc::ServerContext*, const pv1::GetServingStatusRequest*,
                                pv1::GetServingStatusResponse* response) override {
    response->set_ready(false);
    return grpc::Status::OK;
  }
};

// Without a served policy there is no world to read actions in: the episode is refused
// before the arm moves, whether the service serves nothing or cannot say.
TEST_F(GatewayEndToEnd, NoServedPolicyIsRefusedBeforeTheArmMoves) {
  UnreadyPolicyService unready;
  pv1::PolicyService::Service unimplemented;  // GetServingStatus: UNIMPLEMENTED
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  for (auto [service, code, message] :
       {std::tuple<pv1::PolicyService::Service*, ErrorCode, std::string>{
            &unready, ErrorCode::kFailedPrecondition, "serves no whole policy yet"},
        {&unimplemented, ErrorCode::kUnavailable, "GetServingStatus failed"}}) {
    services::ServerRuntime server({"127.0.0.1:0", 1 << 20, {service}, {}});
    auto stub = pv1::PolicyService::NewStub(
        grpc::CreateChannel(loopback(server.port()), grpc::InsecureChannelCredentials()));
    GatewayEpisodeRunner runner(config, *controller_, *stub, recorder());
    const auto before = arm_->state();
    try {
      runner.run(episode(904), not_interrupted_);
      ADD_FAILURE() << "ran without a served policy";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), code);
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
    EXPECT_EQ(arm_->state().sequence, before.sequence);
    server.shutdown(std::chrono::milliseconds(100));
  }
}

TEST_F(GatewayEndToEnd, ABrokenReadingEndsTheEpisodeNotTheGateway) {
  BrokenReadingController broken;
  services::ServerRuntime broken_server(
      {"127.0.0.1:0",
       1 << 20,
       {static_cast<rv1::RobotControllerService::Service*>(&broken),
        static_cast<rv1::SimulatedSceneService::Service*>(&broken)},
       {}});
  ControllerLink link(
      grpc::CreateChannel(loopback(broken_server.port()), grpc::InsecureChannelCredentials()),
      loopback(broken_server.port()), std::chrono::milliseconds(2000));
  link.acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, link, *policy_stub_, recorder());
  for (std::uint64_t seed : {1u, 2u}) {  // the second episode runs as well
    const EpisodeReport report = runner.run(episode(seed), not_interrupted_);
    EXPECT_EQ(report.end, EpisodeEnd::kControllerFault);
    EXPECT_NE(report.reason.find("finger_gap_m"), std::string::npos) << report.reason;
    EXPECT_EQ(report.steps, 0);
  }
  EXPECT_EQ(broken.targets.load(), 0);  // nothing was sent
  EXPECT_EQ(count("bad_reading"), 2);
  broken_server.shutdown(std::chrono::milliseconds(100));
}

TEST_F(GatewayEndToEnd, ASecondGatewayIsRefusedTheLease) {
  controller_->acquire_lease("first", std::chrono::milliseconds(5000));
  ControllerLink second(
      grpc::CreateChannel(loopback(controller_server_->port()), grpc::InsecureChannelCredentials()),
      loopback(controller_server_->port()), std::chrono::milliseconds(2000));
  try {
    second.acquire_lease("second", std::chrono::milliseconds(5000));
    FAIL() << "two gateways hold the arm";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("\"first\""), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pnp::gateway
