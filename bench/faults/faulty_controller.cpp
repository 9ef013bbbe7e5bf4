#include "bench/faults/faulty_controller.h"

#include <limits>
#include <thread>

#include "bench/faults/forward_call.h"

namespace pnp::faults {
namespace {

namespace rv1 = robot::v1;

// One of three readings no controller should send, picked by the call count it fired on.
void break_reading(rv1::GetStateResponse& response, int variant) {
  rv1::ControllerFeedback& state = *response.mutable_state();
  switch (variant % 3) {
    case 0:
      state.mutable_commanded()->mutable_position()->set_x_m(
          std::numeric_limits<double>::quiet_NaN());
      break;
    case 1:  // what a controller without an orientation estimate might send
      state.mutable_measured()->mutable_orientation()->Clear();
      break;
    default:  // perception lost the object
      state.clear_object();
      break;
  }
}

}  // namespace

FaultyController::FaultyController(const std::shared_ptr<grpc::Channel>& upstream,
                                   FaultSwitch& faults, std::chrono::milliseconds stall)
    : upstream_(rv1::RobotControllerService::NewStub(upstream)), faults_(faults), stall_(stall) {}

void FaultyController::wait_out_stall(const grpc::ServerContext& context) const {
  while (FaultSwitch::Clock::now() < faults_.controller_stalled_until() && !context.IsCancelled()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void FaultyController::emergency_stop_from_the_cell() {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  rv1::StopRequest request;
  request.set_reason("injected: a person in the cell pressed the E-stop");
  request.set_kind(rv1::STOP_KIND_EMERGENCY);
  rv1::StopResponse response;
  upstream_->Stop(&context, request, &response);  // its effect is read back by GetState
}

grpc::Status FaultyController::AcquireLease(grpc::ServerContext* context,
                                            const rv1::AcquireLeaseRequest* request,
                                            rv1::AcquireLeaseResponse* response) {
  return forward(*context, &rv1::RobotControllerService::Stub::AcquireLease, *request, response);
}

grpc::Status FaultyController::ReleaseLease(grpc::ServerContext* context,
                                            const rv1::ReleaseLeaseRequest* request,
                                            rv1::ReleaseLeaseResponse* response) {
  return forward(*context, &rv1::RobotControllerService::Stub::ReleaseLease, *request, response);
}

grpc::Status FaultyController::GetState(grpc::ServerContext* context,
                                        const rv1::GetStateRequest* request,
                                        rv1::GetStateResponse* response) {
  const std::optional<FaultKind> fault = faults_.fire(CallSite::kGetState);
  if (fault == FaultKind::kControllerStall) {
    faults_.stall_controller_until(FaultSwitch::Clock::now() + stall_);
  }
  wait_out_stall(*context);
  if (context->IsCancelled()) return {grpc::StatusCode::CANCELLED, "the caller left"};
  grpc::Status status = forward_call(
      *context, *upstream_, &rv1::RobotControllerService::Stub::GetState, *request, response);
  if (status.ok() && fault == FaultKind::kBrokenReading) {
    break_reading(*response, static_cast<int>(response->state().sequence()));
  }
  return status;
}

grpc::Status FaultyController::Stop(grpc::ServerContext* context, const rv1::StopRequest* request,
                                    rv1::StopResponse* response) {
  return forward(*context, &rv1::RobotControllerService::Stub::Stop, *request, response);
}

grpc::Status FaultyController::Resume(grpc::ServerContext* context,
                                      const rv1::ResumeRequest* request,
                                      rv1::ResumeResponse* response) {
  return forward(*context, &rv1::RobotControllerService::Stub::Resume, *request, response);
}

grpc::Status FaultyController::StreamPoseTargets(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<rv1::ControllerFeedback, rv1::StreamPoseTargetsRequest>* stream) {
  grpc::ClientContext upstream_context;
  auto upstream = upstream_->StreamPoseTargets(&upstream_context);
  rv1::StreamPoseTargetsRequest request;
  rv1::ControllerFeedback feedback;
  while (!context->IsCancelled() && stream->Read(&request)) {
    const bool target = request.request_case() == rv1::StreamPoseTargetsRequest::kTarget;
    const std::optional<FaultKind> fault = target ? faults_.fire(CallSite::kTarget) : std::nullopt;
    if (fault == FaultKind::kDroppedStream) {  // the target never arrives
      upstream_context.TryCancel();
      return {grpc::StatusCode::UNAVAILABLE, "injected: the network dropped the drive stream"};
    }
    if (!upstream->Write(request)) break;
    if (!target) continue;  // the opening lease_id has no feedback
    if (!upstream->Read(&feedback)) break;
    if (fault == FaultKind::kEmergencyStop) emergency_stop_from_the_cell();
    wait_out_stall(*context);
    if (!stream->Write(feedback)) break;
  }
  upstream->WritesDone();
  const grpc::Status status = upstream->Finish();
  if (context->IsCancelled()) return {grpc::StatusCode::CANCELLED, "the caller left"};
  return status;
}

ForwardedScene::ForwardedScene(const std::shared_ptr<grpc::Channel>& upstream)
    : upstream_(rv1::SimulatedSceneService::NewStub(upstream)) {}

grpc::Status ForwardedScene::ResetScene(grpc::ServerContext* context,
                                        const rv1::ResetSceneRequest* request,
                                        rv1::ResetSceneResponse* response) {
  return forward_call(*context, *upstream_, &rv1::SimulatedSceneService::Stub::ResetScene, *request,
                      response);
}

}  // namespace pnp::faults
