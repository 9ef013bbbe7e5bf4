#include "bench/faults/faulty_policy.h"

#include <thread>

#include "bench/faults/forward_call.h"

namespace pnp::faults {

namespace pv1 = policy::v1;

FaultyPolicy::FaultyPolicy(const std::shared_ptr<grpc::Channel>& upstream, FaultSwitch& faults,
                           std::chrono::milliseconds stall)
    : upstream_(pv1::PolicyService::NewStub(upstream)), faults_(faults), stall_(stall) {}

grpc::Status FaultyPolicy::Predict(grpc::ServerContext* context, const pv1::PredictRequest* request,
                                   pv1::PredictResponse* response) {
  return forward_call(*context, *upstream_, &pv1::PolicyService::Stub::Predict, *request, response);
}

grpc::Status FaultyPolicy::PredictSession(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<pv1::PredictSessionResponse, pv1::PredictSessionRequest>* stream) {
  grpc::ClientContext upstream_context;
  auto upstream = upstream_->PredictSession(&upstream_context);
  pv1::PredictSessionRequest request;
  pv1::PredictSessionResponse response;
  while (!context->IsCancelled() && stream->Read(&request)) {
    const bool stalled = faults_.fire(CallSite::kPredict) == FaultKind::kInferenceStall;
    if (!upstream->Write(request) || !upstream->Read(&response)) break;
    if (faults_.policy_dives()) response.mutable_prediction()->mutable_action()->set_dz(-1);
    const auto until = FaultSwitch::Clock::now() + stall_;
    while (stalled && FaultSwitch::Clock::now() < until && !context->IsCancelled()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (context->IsCancelled() || !stream->Write(response)) break;
  }
  if (context->IsCancelled()) {
    upstream_context.TryCancel();
    return {grpc::StatusCode::CANCELLED, "the caller left"};
  }
  upstream->WritesDone();
  return upstream->Finish();
}

grpc::Status FaultyPolicy::PromoteCheckpoint(grpc::ServerContext* context,
                                             const pv1::PromoteCheckpointRequest* request,
                                             pv1::PromoteCheckpointResponse* response) {
  return forward_call(*context, *upstream_, &pv1::PolicyService::Stub::PromoteCheckpoint, *request,
                      response);
}

grpc::Status FaultyPolicy::GetServingStatus(grpc::ServerContext* context,
                                            const pv1::GetServingStatusRequest* request,
                                            pv1::GetServingStatusResponse* response) {
  return forward_call(*context, *upstream_, &pv1::PolicyService::Stub::GetServingStatus, *request,
                      response);
}

grpc::Status FaultyPolicy::Ping(grpc::ServerContext* context, const pv1::PingRequest* request,
                                pv1::PingResponse* response) {
  return forward_call(*context, *upstream_, &pv1::PolicyService::Stub::Ping, *request, response);
}

}  // namespace pnp::faults
