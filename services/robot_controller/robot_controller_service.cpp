#include "services/robot_controller/robot_controller_service.h"

#include <cmath>

#include "common/error.h"
#include "services/common/access_control.h"
#include "services/common/robot_convert.h"
#include "services/common/server_runtime.h"
#include "services/common/status.h"
#include "services/common/time_convert.h"
#include "services/robot_controller/feedback_convert.h"

namespace pnp::services {
namespace {

robot::TargetRequest from_proto(const robot::v1::PoseTarget& target) {
  const geometry::Pose pose = services::from_proto(target.pose());
  robot::TargetRequest request{
      target.sequence(),        target.frame_id(),          pose.position_m, pose.orientation,
      target.gripper_width_m(), target.max_speed_m_per_s(), std::nullopt};
  if (target.has_stamp()) {
    try {
      request.stamp = services::from_proto(target.stamp(), "stamp");
    } catch (const Error&) {  // refused as stale (it names the stamp), not a broken stream
      request.stamp = std::chrono::system_clock::time_point{};
    }
  }
  return request;
}

}  // namespace

void require_lease_id(const std::string& lease_id) {
  if (lease_id.empty()) throw_invalid_argument("lease_id", "the id AcquireLease returned", "\"\"");
}

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
    auto slot = admit_stream(limits_, *context, "StreamPoseTargets");
    robot::v1::StreamPoseTargetsRequest request;
    if (!stream->Read(&request)) return grpc::Status::OK;  // closed before opening
    slot.touch();
    if (request.request_case() != robot::v1::StreamPoseTargetsRequest::kLeaseId) {
      throw_invalid_argument("request", "a lease_id as the stream's first message", "a target");
    }
    const std::string lease_id = request.lease_id();
    require_lease_id(lease_id);
    const std::uint64_t stream_id = arm_.open_stream(lease_id);
    {  // this stream supersedes the one before it: end that one now
      std::lock_guard lock(stream_mutex_);
      if (current_stream_ != nullptr) current_stream_->TryCancel();
      current_stream_ = context;
    }
    struct Forget {  // on every way out: no later stream may cancel this finished one
      RobotControllerServiceImpl& self;
      grpc::ServerContext* context;
      ~Forget() {
        std::lock_guard lock(self.stream_mutex_);
        if (self.current_stream_ == context) self.current_stream_ = nullptr;
      }
    } forget{*this, context};
    robot::v1::ControllerFeedback feedback;
    while (!context->IsCancelled() && stream->Read(&request)) {
      slot.touch();
      if (request.request_case() != robot::v1::StreamPoseTargetsRequest::kTarget) {
        throw_invalid_argument("request", "a target after the opening lease_id", "a lease_id");
      }
      const auto report = arm_.take_target(lease_id, stream_id, from_proto(request.target()));
      to_proto(report, arm_.base_frame_id(), feedback);
      if (!stream->Write(feedback)) break;
    }
    if (context->IsCancelled()) {
      return grpc::Status(grpc::StatusCode::CANCELLED,
                          "cancelled (by the client, or superseded by a newer stream)");
    }
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::GetState(grpc::ServerContext*,
                                                  const robot::v1::GetStateRequest*,
                                                  robot::v1::GetStateResponse* response) {
  return guarded([&] {
    const robot::ControllerReport state = arm_.state();
    to_proto(state, arm_.base_frame_id(), *response->mutable_state());
    response->set_lease_holder(arm_.lease_holder().value_or(""));
    response->set_lockstep(arm_.lockstep());
    response->set_stop_kind(to_proto(state.stop_kind));
    response->set_stop_reason(state.stop_reason);
    response->set_tcp_from_flange_m(arm_.tcp_from_flange_m());
    return grpc::Status::OK;
  });
}

grpc::Status RobotControllerServiceImpl::Stop(grpc::ServerContext*,
                                              const robot::v1::StopRequest* request,
                                              robot::v1::StopResponse* response) {
  return guarded([&] {
    const robot::StopKind kind = stop_kind_from_proto(request->kind());
    const robot::ControllerReport state = arm_.stop(request->reason(), kind);
    log_event("robot_sim", "stop",
              {{"kind", robot::stop_kind_name(kind)},
               {"reason", request->reason()},
               {"in_force", robot::stop_kind_name(state.stop_kind)}});
    to_proto(state, arm_.base_frame_id(), *response->mutable_state());
    return grpc::Status::OK;
  });
}

std::string clearing_operator(const std::string& principal, const std::string& stated) {
  return principal.empty() ? stated : principal;
}

grpc::Status RobotControllerServiceImpl::Resume(grpc::ServerContext* context,
                                                const robot::v1::ResumeRequest* request,
                                                robot::v1::ResumeResponse* response) {
  return guarded([&] {
    const std::string by = clearing_operator(principal_of(*context), request->operator_name());
    const auto cleared = arm_.resume({request->lease_id(), request->acknowledged_reason(), by});
    log_event("robot_sim", "stop_cleared",
              {{"kind", robot::stop_kind_name(cleared.kind)},
               {"reason", cleared.reason},
               {"operator", by},
               {"operator_name_stated", request->operator_name()},
               {"by_lease_holder", cleared.kind == robot::StopKind::kProtective}});
    response->set_cleared_kind(to_proto(cleared.kind));
    response->set_cleared_reason(cleared.reason);
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
