#include "clients/robot_gateway/controller_link.h"

#include "services/common/status.h"
#include "services/common/time_convert.h"

namespace pnp::gateway {

namespace rv1 = robot::v1;

struct ControllerLink::Stream {
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientReaderWriter<rv1::StreamPoseTargetsRequest, rv1::ControllerFeedback>>
      rw;
  std::optional<StreamMailbox<rv1::ControllerFeedback>> replies;
  rv1::StreamPoseTargetsRequest request;
};

ControllerLink::ControllerLink(std::shared_ptr<grpc::Channel> channel, std::string address,
                               std::chrono::milliseconds rpc_timeout)
    : address_(std::move(address)),
      rpc_timeout_(rpc_timeout),
      controller_(rv1::RobotControllerService::NewStub(channel)),
      scene_(rv1::SimulatedSceneService::NewStub(channel)) {}

ControllerLink::~ControllerLink() {
  try {
    close_stream();
    release_lease();
  } catch (const std::exception&) {  // the controller is gone: its lease expires by itself
  }
}

std::unique_ptr<grpc::ClientContext> ControllerLink::context(
    std::chrono::milliseconds timeout) const {
  auto c = std::make_unique<grpc::ClientContext>();
  c->set_deadline(std::chrono::system_clock::now() + timeout);
  return c;
}

void ControllerLink::acquire_lease(const std::string& client_name,
                                   std::chrono::milliseconds timeout) {
  rv1::AcquireLeaseRequest request;
  request.set_client_name(client_name);
  services::to_proto(std::chrono::nanoseconds(timeout), *request.mutable_timeout());
  rv1::AcquireLeaseResponse response;
  services::throw_if_error(
      controller_->AcquireLease(context(rpc_timeout_).get(), request, &response), "AcquireLease",
      address_);
  lease_id_ = response.lease_id();
}

void ControllerLink::release_lease() {
  if (lease_id_.empty()) return;
  rv1::ReleaseLeaseRequest request;
  request.set_lease_id(lease_id_);
  rv1::ReleaseLeaseResponse response;
  const auto status = controller_->ReleaseLease(context(rpc_timeout_).get(), request, &response);
  lease_id_.clear();
  services::throw_if_error(status, "ReleaseLease", address_);
}

rv1::GetStateResponse ControllerLink::state() {
  rv1::GetStateResponse response;
  services::throw_if_error(controller_->GetState(context(rpc_timeout_).get(), {}, &response),
                           "GetState", address_);
  return response;
}

rv1::ResetSceneResponse ControllerLink::reset_scene(std::uint64_t seed) {
  rv1::ResetSceneRequest request;
  request.set_lease_id(lease_id_);
  request.set_seed(seed);
  rv1::ResetSceneResponse response;
  services::throw_if_error(scene_->ResetScene(context(rpc_timeout_).get(), request, &response),
                           "ResetScene", address_);
  return response;
}

rv1::StopResponse ControllerLink::stop(const std::string& reason) {
  rv1::StopRequest request;
  request.set_reason(reason);
  rv1::StopResponse response;
  services::throw_if_error(controller_->Stop(context(rpc_timeout_).get(), request, &response),
                           "Stop", address_);
  return response;
}

void ControllerLink::resume() {
  rv1::ResumeRequest request;
  request.set_lease_id(lease_id_);
  rv1::ResumeResponse response;
  services::throw_if_error(controller_->Resume(context(rpc_timeout_).get(), request, &response),
                           "Resume", address_);
}

void ControllerLink::open_stream() {
  close_stream();
  stream_ = std::make_unique<Stream>();
  stream_->rw = controller_->StreamPoseTargets(&stream_->context);
  Stream& s = *stream_;
  s.replies.emplace([&s](rv1::ControllerFeedback& m) { return s.rw->Read(&m); });
  s.request.set_lease_id(lease_id_);
  if (!s.rw->Write(s.request)) {
    close_stream();
    throw Error(ErrorCode::kUnavailable,
                "StreamPoseTargets (" + address_ + "): the controller closed the stream");
  }
}

bool ControllerLink::send(const rv1::PoseTarget& target) {
  if (!stream_) throw_failed_precondition("send: the drive stream is not open");
  *stream_->request.mutable_target() = target;
  return stream_->rw->Write(stream_->request);
}

std::optional<rv1::ControllerFeedback> ControllerLink::feedback(Clock::time_point deadline) {
  if (!stream_) throw_failed_precondition("feedback: the drive stream is not open");
  auto reply = stream_->replies->next(deadline);
  if (!reply && stream_->replies->ended()) {
    // The controller ended the stream: its status says why (e.g. a lost lease).
    stream_->replies.reset();
    const grpc::Status status = stream_->rw->Finish();
    stream_.reset();
    services::throw_if_error(status, "StreamPoseTargets", address_);
    throw Error(ErrorCode::kUnavailable,
                "StreamPoseTargets (" + address_ + "): the controller ended the stream");
  }
  return reply;
}

void ControllerLink::close_stream() {
  if (!stream_) return;
  stream_->rw->WritesDone();
  stream_->context.TryCancel();  // do not wait for a stalled controller
  stream_->replies.reset();
  stream_->rw->Finish().ok();
  stream_.reset();
}

}  // namespace pnp::gateway
