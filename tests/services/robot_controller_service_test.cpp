// pnp.robot.v1 over the controller stand-in, in process over loopback with real stubs:
// the lease, the drive stream's rules, E-stop and resume, scene resets, and refusals.

#include "services/robot_sim/robot_controller_service.h"

#include <gtest/gtest.h>

#include "services/common/robot_convert.h"
#include "services/common/server_runtime.h"

namespace pnp::services {
namespace {

namespace rv1 = robot::v1;

arm_sim::StandInOptions lockstep() {
  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kLockstep;
  return options;
}

class RobotControllerServiceTest : public ::testing::Test {
 protected:
  RobotControllerServiceTest()
      : arm_(lockstep()),
        controller_(arm_),
        scene_(arm_),
        server_({"127.0.0.1:0", 1 << 20, {&controller_, &scene_}, {}}) {
    auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(server_.port()),
                                       grpc::InsecureChannelCredentials());
    stub_ = rv1::RobotControllerService::NewStub(channel);
    scene_stub_ = rv1::SimulatedSceneService::NewStub(channel);
  }
  ~RobotControllerServiceTest() override { server_.shutdown(std::chrono::milliseconds(200)); }

  grpc::Status acquire(const std::string& name, std::string* lease_id) {
    grpc::ClientContext context;
    rv1::AcquireLeaseRequest request;
    request.set_client_name(name);
    rv1::AcquireLeaseResponse response;
    const auto status = stub_->AcquireLease(&context, request, &response);
    if (lease_id) *lease_id = response.lease_id();
    return status;
  }
  rv1::GetStateResponse state() {
    grpc::ClientContext context;
    rv1::GetStateResponse response;
    EXPECT_TRUE(stub_->GetState(&context, {}, &response).ok());
    return response;
  }
  grpc::Status reset(const std::string& lease_id, std::uint64_t seed,
                     rv1::ResetSceneResponse* out = nullptr) {
    grpc::ClientContext context;
    rv1::ResetSceneRequest request;
    request.set_lease_id(lease_id);
    request.set_seed(seed);
    rv1::ResetSceneResponse response;
    const auto status = scene_stub_->ResetScene(&context, request, &response);
    if (out) *out = response;
    return status;
  }
  // A target `dz_m` above the current commanded pose.
  rv1::PoseTarget target_above(std::uint64_t sequence, double dz_m) {
    const auto s = state().state();
    rv1::PoseTarget t;
    t.set_sequence(sequence);
    t.set_frame_id(s.frame_id());
    *t.mutable_pose() = s.commanded();
    t.mutable_pose()->mutable_position()->set_z_m(s.commanded().position().z_m() + dz_m);
    t.set_gripper_width_m(0.08);
    return t;
  }

  arm_sim::ControllerStandIn arm_;
  RobotControllerServiceImpl controller_;
  SimulatedSceneServiceImpl scene_;
  ServerRuntime server_;
  std::unique_ptr<rv1::RobotControllerService::Stub> stub_;
  std::unique_ptr<rv1::SimulatedSceneService::Stub> scene_stub_;
};

TEST_F(RobotControllerServiceTest, LeaseIsExclusiveAndNamedInRefusals) {
  std::string lease;
  ASSERT_TRUE(acquire("gateway-a", &lease).ok());
  EXPECT_EQ(state().lease_holder(), "gateway-a");
  EXPECT_TRUE(state().lockstep());
  const auto refused = acquire("gateway-b", nullptr);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(refused.error_message().find("gateway-a"), std::string::npos);
  EXPECT_EQ(acquire("", nullptr).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  grpc::ClientContext context;
  rv1::ReleaseLeaseRequest release;
  release.set_lease_id("not-a-lease");
  rv1::ReleaseLeaseResponse released;
  EXPECT_EQ(stub_->ReleaseLease(&context, release, &released).error_code(),
            grpc::StatusCode::NOT_FOUND);
  grpc::ClientContext context2;
  release.set_lease_id(lease);
  EXPECT_TRUE(stub_->ReleaseLease(&context2, release, &released).ok());
  EXPECT_TRUE(acquire("gateway-b", nullptr).ok());
}

TEST_F(RobotControllerServiceTest, AcquireRefusesAnEmptyNameOrABadTimeout) {
  grpc::ClientContext context;
  rv1::AcquireLeaseRequest request;
  rv1::AcquireLeaseResponse response;
  const auto status = stub_->AcquireLease(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("client_name"), std::string::npos);
  grpc::ClientContext context2;
  request.set_client_name("g");
  request.mutable_timeout()->set_seconds(-1);
  const auto negative = stub_->AcquireLease(&context2, request, &response);
  EXPECT_EQ(negative.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(negative.error_message().find("timeout"), std::string::npos);
}

TEST_F(RobotControllerServiceTest, StreamNeedsTheLeaseFirst) {
  grpc::ClientContext context;
  auto stream = stub_->StreamPoseTargets(&context);
  rv1::StreamPoseTargetsRequest open;
  open.set_lease_id("forged");
  stream->Write(open);
  stream->WritesDone();
  rv1::ControllerFeedback feedback;
  EXPECT_FALSE(stream->Read(&feedback));
  const auto status = stream->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("lease_id"), std::string::npos);

  grpc::ClientContext context2;
  auto stream2 = stub_->StreamPoseTargets(&context2);
  rv1::StreamPoseTargetsRequest target;
  *target.mutable_target() = target_above(1, 0.0);
  stream2->Write(target);
  stream2->WritesDone();
  EXPECT_FALSE(stream2->Read(&feedback));
  EXPECT_EQ(stream2->Finish().error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(RobotControllerServiceTest, EveryTargetGetsOneFeedbackAndBadOnesAStatus) {
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  rv1::ResetSceneResponse scene;
  ASSERT_TRUE(reset(lease, 7, &scene).ok());
  EXPECT_EQ(scene.state().mode(), rv1::CONTROLLER_MODE_IDLE);

  grpc::ClientContext context;
  auto stream = stub_->StreamPoseTargets(&context);
  rv1::StreamPoseTargetsRequest request;
  request.set_lease_id(lease);
  ASSERT_TRUE(stream->Write(request));
  auto send = [&](const rv1::PoseTarget& t) {
    *request.mutable_target() = t;
    EXPECT_TRUE(stream->Write(request));
    rv1::ControllerFeedback feedback;
    EXPECT_TRUE(stream->Read(&feedback));
    return feedback;
  };
  const auto ok = send(target_above(1, 0.02));
  EXPECT_EQ(ok.status(), rv1::CONTROLLER_STATUS_OK);
  EXPECT_EQ(ok.sequence(), 1u);
  EXPECT_EQ(ok.joint_positions_rad_size(), 7);
  EXPECT_TRUE(ok.has_object());

  const auto replayed = send(target_above(1, 0.02));  // sequence must increase
  EXPECT_EQ(replayed.status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);
  ASSERT_EQ(replayed.errors_size(), 1);
  EXPECT_NE(replayed.errors(0).find("sequence"), std::string::npos);

  auto wrong_frame = target_above(2, 0.0);
  wrong_frame.set_frame_id("world");
  EXPECT_EQ(send(wrong_frame).status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);

  auto nan = target_above(3, 0.0);
  nan.mutable_pose()->mutable_position()->set_x_m(std::nan(""));
  EXPECT_EQ(send(nan).status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);

  auto bad_quaternion = target_above(4, 0.0);
  bad_quaternion.mutable_pose()->mutable_orientation()->set_w(3);
  EXPECT_EQ(send(bad_quaternion).status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);

  EXPECT_EQ(send(target_above(5, 2.0)).status(), rv1::CONTROLLER_STATUS_UNREACHABLE);
  const auto after = send(target_above(6, 0.0));
  EXPECT_EQ(after.status(), rv1::CONTROLLER_STATUS_OK);
  EXPECT_EQ(after.sequence(), 6u);
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_F(RobotControllerServiceTest, StopIsHonouredAtOnceUntilTheHolderResumes) {
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  ASSERT_TRUE(reset(lease, 3).ok());
  grpc::ClientContext stop_context;
  rv1::StopRequest stop;
  stop.set_reason("operator pressed the button");
  rv1::StopResponse stopped;
  ASSERT_TRUE(stub_->Stop(&stop_context, stop, &stopped).ok());  // no lease needed
  EXPECT_EQ(stopped.state().mode(), rv1::CONTROLLER_MODE_STOPPED);

  grpc::ClientContext context;
  auto stream = stub_->StreamPoseTargets(&context);
  rv1::StreamPoseTargetsRequest request;
  request.set_lease_id(lease);
  stream->Write(request);
  *request.mutable_target() = target_above(1, 0.03);
  stream->Write(request);
  rv1::ControllerFeedback feedback;
  ASSERT_TRUE(stream->Read(&feedback));
  EXPECT_EQ(feedback.status(), rv1::CONTROLLER_STATUS_STOPPED);
  EXPECT_EQ(feedback.mode(), rv1::CONTROLLER_MODE_STOPPED);
  stream->WritesDone();
  stream->Finish();

  EXPECT_EQ(reset(lease, 4).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  grpc::ClientContext resume_context;
  rv1::ResumeRequest resume;
  resume.set_lease_id("forged");
  rv1::ResumeResponse resumed;
  EXPECT_EQ(stub_->Resume(&resume_context, resume, &resumed).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  grpc::ClientContext resume_context2;
  resume.set_lease_id(lease);
  EXPECT_TRUE(stub_->Resume(&resume_context2, resume, &resumed).ok());
  EXPECT_NE(state().state().mode(), rv1::CONTROLLER_MODE_STOPPED);
}

TEST_F(RobotControllerServiceTest, ResetSceneNeedsTheLeaseAndPlacesTheSeedsEpisode) {
  EXPECT_EQ(reset("", 1).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(reset("forged", 1).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  rv1::ResetSceneResponse a, b, c;
  ASSERT_TRUE(reset(lease, 11, &a).ok());
  ASSERT_TRUE(reset(lease, 12, &b).ok());
  ASSERT_TRUE(reset(lease, 11, &c).ok());
  EXPECT_EQ(a.goal().x_m(), c.goal().x_m());
  EXPECT_EQ(a.state().object().pose().position().y_m(), c.state().object().pose().position().y_m());
  EXPECT_NE(a.goal().x_m(), b.goal().x_m());
  EXPECT_EQ(a.state().frame_id(), "panda_link0");
}

}  // namespace
}  // namespace pnp::services
