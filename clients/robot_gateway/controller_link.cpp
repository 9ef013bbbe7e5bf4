#include "clients/robot_gateway/controller_link.h"

#include <algorithm>

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
                               std::chrono::milliseconds rpc_timeout,
                               const std::atomic<bool>& interrupted)
    : address_(std::move(address)),
      rpc_timeout_(rpc_timeout),
      interrupted_(interrupted),
      controller_(rv1::RobotControllerService::NewStub(channel)),
      scene_(rv1::SimulatedSceneService::NewStub(channel)) {}

ControllerLink::~ControllerLink() {
  try {
    close_stream();
    release_lease();
  } catch (const std::exception&) {  // the controller is gone: its lease expires by itself
  }
}

// Asynchronous under the hood so that the wait can look at the interrupt: a synchronous
// call would hold the gateway for its whole deadline.
template <typename Response, typename Start>
std::optional<Response> ControllerLink::call(const char* what, std::chrono::milliseconds timeout,
                                             bool interruptible, Start start) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  grpc::CompletionQueue queue;
  Response response;
  grpc::Status status;
  auto reader = start(&context, &queue);
  int tag = 0;
  reader->Finish(&response, &status, &tag);
  bool cancelled = false;
  void* got = nullptr;
  bool ok = false;
  for (;;) {
    const auto next = queue.AsyncNext(&got, &ok, std::chrono::system_clock::now() + kInterruptPoll);
    if (next == grpc::CompletionQueue::GOT_EVENT || next == grpc::CompletionQueue::SHUTDOWN) break;
    if (interruptible && !cancelled && interrupted_.load()) {
      context.TryCancel();  // the call then completes at once, CANCELLED
      cancelled = true;
    }
  }
  queue.Shutdown();
  while (queue.Next(&got, &ok)) {
  }
  if (cancelled) {
    throw Error(ErrorCode::kCancelled,
                std::string(what) + " (" + address_ + "): interrupted by the operator");
  }
  if (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) return std::nullopt;
  services::throw_if_error(status, what, address_);
  return response;
}

void ControllerLink::acquire_lease(const std::string& client_name,
                                   std::chrono::milliseconds timeout) {
  rv1::AcquireLeaseRequest request;
  request.set_client_name(client_name);
  services::to_proto(std::chrono::nanoseconds(timeout), *request.mutable_timeout());
  const auto response = call<rv1::AcquireLeaseResponse>(
      "AcquireLease", rpc_timeout_, true, [&](grpc::ClientContext* c, grpc::CompletionQueue* q) {
        return controller_->AsyncAcquireLease(c, request, q);
      });
  if (!response) throw Error(ErrorCode::kUnavailable, "AcquireLease (" + address_ + "): no answer");
  lease_id_ = response->lease_id();
  client_name_ = client_name;
  lease_timeout_ = timeout;
}

void ControllerLink::reacquire_lease() {
  if (client_name_.empty())
    throw Error(ErrorCode::kFailedPrecondition, "no lease was acquired to take again");
  acquire_lease(client_name_, lease_timeout_);
}

void ControllerLink::release_lease() {
  if (lease_id_.empty()) return;
  rv1::ReleaseLeaseRequest request;
  request.set_lease_id(lease_id_);
  lease_id_.clear();
  // After Ctrl-C the operator waits for the gateway: a stalled controller gets a short
  // try, and its lease lapses by itself anyway (the controller's dead-man).
  const auto timeout =
      interrupted_.load() ? std::min(rpc_timeout_, kReleaseAfterInterrupt) : rpc_timeout_;
  call<rv1::ReleaseLeaseResponse>("ReleaseLease", timeout, false,
                                  [&](grpc::ClientContext* c, grpc::CompletionQueue* q) {
                                    return controller_->AsyncReleaseLease(c, request, q);
                                  });
}

std::optional<rv1::GetStateResponse> ControllerLink::state(std::chrono::milliseconds timeout) {
  const rv1::GetStateRequest request;
  return call<rv1::GetStateResponse>("GetState", timeout, true,
                                     [&](grpc::ClientContext* c, grpc::CompletionQueue* q) {
                                       return controller_->AsyncGetState(c, request, q);
                                     });
}

rv1::GetStateResponse ControllerLink::state() {
  auto response = state(rpc_timeout_);
  if (!response) {
    throw Error(ErrorCode::kUnavailable, "GetState (" + address_ + "): no answer within " +
                                             std::to_string(rpc_timeout_.count()) + " ms");
  }
  return std::move(*response);
}

rv1::ResetSceneResponse ControllerLink::reset_scene(std::uint64_t seed) {
  rv1::ResetSceneRequest request;
  request.set_lease_id(lease_id_);
  request.set_seed(seed);
  auto response = call<rv1::ResetSceneResponse>(
      "ResetScene", rpc_timeout_, true, [&](grpc::ClientContext* c, grpc::CompletionQueue* q) {
        return scene_->AsyncResetScene(c, request, q);
      });
  if (!response) {
    throw Error(ErrorCode::kUnavailable, "ResetScene (" + address_ + "): no answer within " +
                                             std::to_string(rpc_timeout_.count()) + " ms");
  }
  return std::move(*response);
}

rv1::StopResponse ControllerLink::stop(const std::string& reason, rv1::StopKind kind,
                                       std::chrono::milliseconds timeout) {
  rv1::StopRequest request;
  request.set_reason(reason);
  request.set_kind(kind);
  auto response = call<rv1::StopResponse>("Stop", timeout, false,
                                          [&](grpc::ClientContext* c, grpc::CompletionQueue* q) {
                                            return controller_->AsyncStop(c, request, q);
                                          });
  if (!response) {
    throw Error(ErrorCode::kUnavailable, "Stop (" + address_ + "): no answer within " +
                                             std::to_string(timeout.count()) + " ms");
  }
  return std::move(*response);
}

rv1::ResumeResponse ControllerLink::clear_protective_stop() {
  rv1::ResumeRequest request;
  request.set_lease_id(lease_id_);
  auto response = call<rv1::ResumeResponse>("Resume", rpc_timeout_, true,
                                            [&](grpc::ClientContext* c, grpc::CompletionQueue* q) {
                                              return controller_->AsyncResume(c, request, q);
                                            });
  if (!response) throw Error(ErrorCode::kUnavailable, "Resume (" + address_ + "): no answer");
  return std::move(*response);
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
  auto reply = stream_->replies->next(deadline, &interrupted_, kInterruptPoll);
  if (!reply && interrupted_.load()) {
    throw Error(ErrorCode::kCancelled,
                "StreamPoseTargets (" + address_ + "): interrupted by the operator");
  }
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
  stream_->context.TryCancel();  // do not wait for a stalled controller
  stream_->replies.reset();
  stream_->rw->Finish().ok();
  stream_.reset();
}

}  // namespace pnp::gateway
