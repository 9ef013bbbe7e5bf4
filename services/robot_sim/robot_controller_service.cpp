#include "services/robot_sim/robot_controller_service.h"

#include <cmath>

#include "common/error.h"
#include "services/common/robot_convert.h"
#include "services/common/status.h"
#include "services/common/time_convert.h"
#include "services/robot_sim/feedback_convert.h"

namespace pnp::services {
namespace {

arm_sim::TargetRequest from_proto(const robot::v1::PoseTarget& target) {
  const geometry::Pose pose = services::from_proto(target.pose());
  return {target.sequence(), target.frame_id(),        pose.position_m,
          pose.orientation,  target.gripper_width_m(), target.max_speed_m_per_s()};
}

void require_lease_id(const std::string& lease_id) {
  if (lease_id.empty()) throw_invalid_argument("lease_id", "the id AcquireLease returned", "\"\"");
}

}  // namespace

grpc::Status RobotControllerServiceImpl::AcquireLease(grpc::ServerContext*,
                                                      const robot::v1::AcquireLeaseRequest* request,
                                                      robot::v1::AcquireLeaseResponse* response) {
  return guarded([&] {
    const double timeout_s = request->has_timeout() ? seconds_of(request->timeout()) : 0.0;
    if (request->has_timeout() && !(timeout_s > 0)) {
      throw_invalid_argument("timeout", "a positive duration (or none: the default)",
                             std::to_string(timeout_s) + " s");
    }
    const auto lease = arm_.acquire_lease(request->client_name(), timeout_s);
    response->set_lease_id(lease.id);
    to_proto(std::chrono::nanoseconds(std::llround(lease.timeout_s * 1e9)),
             *response->mutable_timeout());
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::ReleaseLease(grpc::ServerContext*,
                                                      const robot::v1::ReleaseLeaseRequest* request,
                                                      robot::v1::ReleaseLeaseResponse*) {
  return guarded([&] {
    require_lease_id(request->lease_id());
    arm_.release_lease(request->lease_id());
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::StreamPoseTargets(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<robot::v1::ControllerFeedback, robot::v1::StreamPoseTargetsRequest>*
        stream) {
  return guarded([&] {
    robot::v1::StreamPoseTargetsRequest request;
    if (!stream->Read(&request)) return grpc::Status::OK;  // closed before opening
    if (request.request_case() != robot::v1::StreamPoseTargetsRequest::kLeaseId) {
      throw_invalid_argument("request", "a lease_id as the stream's first message", "a target");
    }
    const std::string lease_id = request.lease_id();
    require_lease_id(lease_id);
    arm_.open_stream(lease_id);
    robot::v1::ControllerFeedback feedback;
    while (!context->IsCancelled() && stream->Read(&request)) {
      if (request.request_case() != robot::v1::StreamPoseTargetsRequest::kTarget) {
        throw_invalid_argument("request", "a target after the opening lease_id", "a lease_id");
      }
      const auto report = arm_.take_target(lease_id, from_proto(request.target()));
      to_proto(report, arm_.base_frame_id(), feedback);
      if (!stream->Write(feedback)) break;
    }
    if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::GetState(grpc::ServerContext*,
                                                  const robot::v1::GetStateRequest*,
                                                  robot::v1::GetStateResponse* response) {
  return guarded([&] {
    to_proto(arm_.state(), arm_.base_frame_id(), *response->mutable_state());
    response->set_lease_holder(arm_.lease_holder().value_or(""));
    response->set_lockstep(arm_.clock() == arm_sim::ClockMode::kLockstep);
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::Stop(grpc::ServerContext*,
                                              const robot::v1::StopRequest* request,
                                              robot::v1::StopResponse* response) {
  return guarded([&] {
    to_proto(arm_.stop(request->reason()), arm_.base_frame_id(), *response->mutable_state());
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::Resume(grpc::ServerContext*,
                                                const robot::v1::ResumeRequest* request,
                                                robot::v1::ResumeResponse*) {
  return guarded([&] {
    require_lease_id(request->lease_id());
    arm_.resume(request->lease_id());
    return grpc::Status::OK;
  });
}

grpc::Status SimulatedSceneServiceImpl::ResetScene(grpc::ServerContext*,
                                                   const robot::v1::ResetSceneRequest* request,
                                                   robot::v1::ResetSceneResponse* response) {
  return guarded([&] {
    require_lease_id(request->lease_id());
    const auto reset = arm_.reset_scene(request->lease_id(), request->seed());
    to_proto(reset.report, arm_.base_frame_id(), *response->mutable_state());
    to_proto(reset.goal_base, *response->mutable_goal());
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
