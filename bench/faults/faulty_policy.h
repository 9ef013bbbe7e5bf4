#pragma once
// A fault-injecting proxy in front of the inference service (pnp.policy.v1): every call
// is forwarded over gRPC, and an armed inference stall holds one PredictSession answer
// back for `stall` (as a server stuck in a pause would); while the switch says the policy
// dives, every answer drives straight down (dz = -1).

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>

#include "bench/faults/fault_switch.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"

namespace pnp::faults {

class FaultyPolicy final : public policy::v1::PolicyService::Service {
 public:
  FaultyPolicy(const std::shared_ptr<grpc::Channel>& upstream, FaultSwitch& faults,
               std::chrono::milliseconds stall);

  grpc::Status Predict(grpc::ServerContext* context, const policy::v1::PredictRequest* request,
                       policy::v1::PredictResponse* response) override;
  grpc::Status PredictSession(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<policy::v1::PredictSessionResponse,
                               policy::v1::PredictSessionRequest>* stream) override;
  grpc::Status PromoteCheckpoint(grpc::ServerContext* context,
                                 const policy::v1::PromoteCheckpointRequest* request,
                                 policy::v1::PromoteCheckpointResponse* response) override;
  grpc::Status GetServingStatus(grpc::ServerContext* context,
                                const policy::v1::GetServingStatusRequest* request,
                                policy::v1::GetServingStatusResponse* response) override;
  grpc::Status Ping(grpc::ServerContext* context, const policy::v1::PingRequest* request,
                    policy::v1::PingResponse* response) override;

 private:
  std::unique_ptr<policy::v1::PolicyService::Stub> upstream_;
  FaultSwitch& faults_;
  std::chrono::milliseconds stall_;
};

}  // namespace pnp::faults
