// pnp.robot.v1 over the controller stand-in, in process over loopback with real stubs:
// the lease, the drive stream's rules, E-stop and resume, scene resets, and refusals.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "services/common/robot_convert.h"
#include "services/common/server_runtime.h"
#include "services/common/time_convert.h"
#include "services/robot_sim/simulated_scene_service.h"

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
    to_proto(std::chrono::system_clock::now(), *t.mutable_stamp());
    return t;
  }
  // A drive stream opened with `lease`.
  struct Drive {
    grpc::ClientContext context;
    std::unique_ptr<
        grpc::ClientReaderWriter<rv1::StreamPoseTargetsRequest, rv1::ControllerFeedback>>
        stream;
    rv1::StreamPoseTargetsRequest request;
  };
  std::unique_ptr<Drive> open(const std::string& lease) {
    auto d = std::make_unique<Drive>();
    d->stream = stub_->StreamPoseTargets(&d->context);
    d->request.set_lease_id(lease);
    EXPECT_TRUE(d->stream->Write(d->request));
    return d;
  }
  static std::optional<rv1::ControllerFeedback> send(Drive& d, const rv1::PoseTarget& t) {
    *d.request.mutable_target() = t;
    if (!d.stream->Write(d.request)) return std::nullopt;
    rv1::ControllerFeedback feedback;
    if (!d.stream->Read(&feedback)) return std::nullopt;
    return feedback;
  }
  grpc::Status stop(const std::string& reason, rv1::StopKind kind) {
    grpc::ClientContext context;
    rv1::StopRequest request;
    request.set_reason(reason);
    request.set_kind(kind);
    rv1::StopResponse response;
    return stub_->Stop(&context, request, &response);
  }
  grpc::Status resume(const std::string& lease, const std::string& ack, const std::string& who) {
    grpc::ClientContext context;
    rv1::ResumeRequest request;
    request.set_lease_id(lease);
    request.set_acknowledged_reason(ack);
    request.set_operator_name(who);
    rv1::ResumeResponse response;
    return stub_->Resume(&context, request, &response);
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
  auto take = [&](const rv1::PoseTarget& t) {
    *request.mutable_target() = t;
    EXPECT_TRUE(stream->Write(request));
    rv1::ControllerFeedback feedback;
    EXPECT_TRUE(stream->Read(&feedback));
    return feedback;
  };
  const auto ok = take(target_above(1, 0.02));
  EXPECT_EQ(ok.status(), rv1::CONTROLLER_STATUS_OK);
  EXPECT_EQ(ok.sequence(), 1u);
  EXPECT_EQ(ok.joint_positions_rad_size(), 7);
  EXPECT_TRUE(ok.has_object());

  const auto replayed = take(target_above(1, 0.02));  // sequence must increase
  EXPECT_EQ(replayed.status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);
  ASSERT_EQ(replayed.errors_size(), 1);
  EXPECT_NE(replayed.errors(0).find("sequence"), std::string::npos);

  auto wrong_frame = target_above(2, 0.0);
  wrong_frame.set_frame_id("world");
  EXPECT_EQ(take(wrong_frame).status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);

  auto nan = target_above(3, 0.0);
  nan.mutable_pose()->mutable_position()->set_x_m(std::nan(""));
  EXPECT_EQ(take(nan).status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);

  auto bad_quaternion = target_above(4, 0.0);
  bad_quaternion.mutable_pose()->mutable_orientation()->set_w(3);
  EXPECT_EQ(take(bad_quaternion).status(), rv1::CONTROLLER_STATUS_INVALID_TARGET);

  EXPECT_EQ(take(target_above(5, 2.0)).status(), rv1::CONTROLLER_STATUS_OUTSIDE_LIMITS);
  const auto after = take(target_above(6, 0.0));
  EXPECT_EQ(after.status(), rv1::CONTROLLER_STATUS_OK);
  EXPECT_EQ(after.sequence(), 6u);
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_F(RobotControllerServiceTest, AnEmergencyStopIsClearedOnlyByAnOperatorAcknowledgingIt) {
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  ASSERT_TRUE(reset(lease, 3).ok());
  ASSERT_TRUE(stop("operator pressed the button", rv1::STOP_KIND_UNSPECIFIED).ok());  // no lease
  EXPECT_EQ(state().state().mode(), rv1::CONTROLLER_MODE_STOPPED);
  EXPECT_EQ(state().stop_kind(), rv1::STOP_KIND_EMERGENCY);  // a stop that does not say
  // A later protective stop does not weaken it, nor replace its reason.
  ASSERT_TRUE(stop("gateway fault", rv1::STOP_KIND_PROTECTIVE).ok());
  EXPECT_EQ(state().stop_kind(), rv1::STOP_KIND_EMERGENCY);
  EXPECT_EQ(state().stop_reason(), "operator pressed the button");

  auto drive = open(lease);
  const auto refused = send(*drive, target_above(1, 0.03));
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status(), rv1::CONTROLLER_STATUS_STOPPED);
  EXPECT_EQ(reset(lease, 4).error_code(), grpc::StatusCode::FAILED_PRECONDITION);

  // The lease holder cannot clear it, nor can an operator without the reason.
  const auto by_holder = resume(lease, "", "");
  EXPECT_EQ(by_holder.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(by_holder.error_message().find("operator_name"), std::string::npos);
  const auto wrong = resume(lease, "the button", "ops");
  EXPECT_EQ(wrong.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(wrong.error_message().find("operator pressed the button"), std::string::npos);
  EXPECT_EQ(state().state().mode(), rv1::CONTROLLER_MODE_STOPPED);
  EXPECT_TRUE(resume("", "operator pressed the button", "ops").ok());
  EXPECT_NE(state().state().mode(), rv1::CONTROLLER_MODE_STOPPED);
  EXPECT_EQ(state().stop_kind(), rv1::STOP_KIND_UNSPECIFIED);
  EXPECT_EQ(resume("", "", "ops").error_code(), grpc::StatusCode::FAILED_PRECONDITION);  // none
  EXPECT_EQ(stop("x", static_cast<rv1::StopKind>(9)).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(RobotControllerServiceTest, AProtectiveStopIsClearedByTheLeaseHolder) {
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  ASSERT_TRUE(stop("gateway lost the arm", rv1::STOP_KIND_PROTECTIVE).ok());
  EXPECT_EQ(state().stop_kind(), rv1::STOP_KIND_PROTECTIVE);
  EXPECT_EQ(resume("forged", "", "").error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_TRUE(resume(lease, "", "").ok());
  EXPECT_NE(state().state().mode(), rv1::CONTROLLER_MODE_STOPPED);
}

// A raw client that bypasses the gateway still cannot drive the hand through the table,
// across the cell in one target, or faster than the arm's limit.
TEST_F(RobotControllerServiceTest, TheControllersOwnLimitsHoldWithoutTheGateway) {
  std::string lease;
  ASSERT_TRUE(acquire("raw", &lease).ok());
  ASSERT_TRUE(reset(lease, 5).ok());
  auto drive = open(lease);
  const double floor = robot::ControllerLimits{}.workspace.min_m.z();
  const double z = state().state().commanded().position().z_m();
  auto below_table = target_above(1, floor - z - 0.02);
  const auto table = send(*drive, below_table);
  ASSERT_TRUE(table);
  EXPECT_EQ(table->status(), rv1::CONTROLLER_STATUS_OUTSIDE_LIMITS);
  ASSERT_EQ(table->errors_size(), 1);
  EXPECT_NE(table->errors(0).find("workspace"), std::string::npos) << table->errors(0);

  auto jump = target_above(2, 0.0);  // inside the box, 0.3 m from the commanded pose
  jump.mutable_pose()->mutable_position()->set_y_m(jump.pose().position().y_m() + 0.3);
  const auto far = send(*drive, jump);
  ASSERT_TRUE(far);
  EXPECT_EQ(far->status(), rv1::CONTROLLER_STATUS_OUTSIDE_LIMITS);
  EXPECT_NE(far->errors(0).find("max_step_m"), std::string::npos) << far->errors(0);

  // Half a radian about the hand's axis in one target: a flip, refused here too.
  auto turned = target_above(3, 0.0);
  const auto& o = turned.pose().orientation();
  const Eigen::Quaterniond q = Eigen::Quaterniond(o.w(), o.x(), o.y(), o.z()) *
                               Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  turned.mutable_pose()->mutable_orientation()->set_w(q.w());
  turned.mutable_pose()->mutable_orientation()->set_x(q.x());
  turned.mutable_pose()->mutable_orientation()->set_y(q.y());
  turned.mutable_pose()->mutable_orientation()->set_z(q.z());
  const auto flipped = send(*drive, turned);
  ASSERT_TRUE(flipped);
  EXPECT_EQ(flipped->status(), rv1::CONTROLLER_STATUS_OUTSIDE_LIMITS);
  EXPECT_NE(flipped->errors(0).find("max_rotation_step_rad"), std::string::npos)
      << flipped->errors(0);

  // 10 cm up at 100 m/s: interpolated at the arm's 1.7 m/s, so after one 40 ms period of
  // lockstep physics the Cartesian set point is 6.8 cm up, not at the target.
  const double before = arm_.state().arm.setpoint_base.position_m.z();
  auto fast = target_above(4, 0.1);
  fast.set_max_speed_m_per_s(100);
  const auto taken = send(*drive, fast);
  ASSERT_TRUE(taken);
  EXPECT_EQ(taken->status(), rv1::CONTROLLER_STATUS_OK);
  EXPECT_NEAR(arm_.state().arm.setpoint_base.position_m.z() - before, 1.7 * 0.04, 2e-3);
}

// On the wall clock (a real arm, the stand-in in real time) a target must be fresh; in
// lockstep it must still carry its stamp.
TEST_F(RobotControllerServiceTest, AStaleOrUnstampedTargetIsRefused) {
  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kRealTime;
  arm_sim::ControllerStandIn real_time(options);
  RobotControllerServiceImpl controller(real_time);
  ServerRuntime server({"127.0.0.1:0", 1 << 20, {&controller}, {}});
  auto real_time_stub = rv1::RobotControllerService::NewStub(grpc::CreateChannel(
      "127.0.0.1:" + std::to_string(server.port()), grpc::InsecureChannelCredentials()));
  std::swap(stub_, real_time_stub);
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  {
    auto drive = open(lease);
    auto old = target_above(1, 0.01);
    to_proto(std::chrono::system_clock::now() - std::chrono::seconds(10), *old.mutable_stamp());
    const auto stale = send(*drive, old);
    ASSERT_TRUE(stale);
    EXPECT_EQ(stale->status(), rv1::CONTROLLER_STATUS_STALE);
    EXPECT_NE(stale->errors(0).find("max_target_age_s"), std::string::npos) << stale->errors(0);
    auto future = target_above(2, 0.01);
    to_proto(std::chrono::system_clock::now() + std::chrono::seconds(10), *future.mutable_stamp());
    EXPECT_EQ(send(*drive, future)->status(), rv1::CONTROLLER_STATUS_STALE);
    // Year 8307: beyond what the clock holds (its conversion used to overflow).
    auto far = target_above(3, 0.01);
    far.mutable_stamp()->set_seconds(200'000'000'000);
    EXPECT_EQ(send(*drive, far)->status(), rv1::CONTROLLER_STATUS_STALE);
    drive->context.TryCancel();
  }
  std::swap(stub_, real_time_stub);
  server.shutdown(std::chrono::milliseconds(200));

  ASSERT_TRUE(acquire("g", &lease).ok());  // lockstep
  ASSERT_TRUE(reset(lease, 6).ok());
  auto drive = open(lease);
  auto unstamped = target_above(1, 0.01);
  unstamped.clear_stamp();
  const auto missing = send(*drive, unstamped);
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status(), rv1::CONTROLLER_STATUS_STALE);
  EXPECT_NE(missing->errors(0).find("stamp: missing"), std::string::npos);
  EXPECT_EQ(send(*drive, target_above(2, 0.01))->status(), rv1::CONTROLLER_STATUS_OK);
}

TEST_F(RobotControllerServiceTest, ANewStreamSupersedesTheOldOne) {
  std::string lease;
  ASSERT_TRUE(acquire("g", &lease).ok());
  ASSERT_TRUE(reset(lease, 8).ok());
  auto first = open(lease);
  ASSERT_EQ(send(*first, target_above(5, 0.01))->status(), rv1::CONTROLLER_STATUS_OK);
  auto second = open(lease);
  // Numbering starts again on the new stream; the old one is cancelled.
  ASSERT_EQ(send(*second, target_above(1, 0.01))->status(), rv1::CONTROLLER_STATUS_OK);
  const auto late = send(*first, target_above(6, 0.01));
  if (late) {  // the write may already fail: the stream is cancelled
    EXPECT_EQ(late->status(), rv1::CONTROLLER_STATUS_LEASE_LOST);
  }
  first->stream->WritesDone();
  EXPECT_EQ(first->stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_EQ(state().state().sequence(), 1u);
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

TEST(ClearingOperator, UnderAPolicyIsThePrincipalWhateverTheRequestStates) {
  EXPECT_EQ(clearing_operator("ops", "mallory"), "ops");
  EXPECT_EQ(clearing_operator("ops", ""), "ops");
  // Without a policy there is no principal: the stated name is all there is.
  EXPECT_EQ(clearing_operator("", "alice"), "alice");
  EXPECT_EQ(clearing_operator("", ""), "");
}

}  // namespace
}  // namespace pnp::services
