#pragma once
// pnp.sim.v1.SimulationService over an EnvRegistry. Every request is validated whole
// before any environment moves: a bad action for environment 3 refuses the batch's step,
// it does not step environments 0-2 and then fail.

#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "services/common/metrics_registry.h"
#include "services/common/stream_limits.h"
#include "services/sim/env_registry.h"

namespace pnp::services {

class SimServiceImpl final : public sim::v1::SimulationService::Service {
 public:
  // With `metrics` (which must outlive the service), counts pnp_env_steps_total; `limits`
  // (null: none; must outlive it too) bounds the rollout streams.
  explicit SimServiceImpl(MetricsRegistry* metrics = nullptr, StreamLimits* limits = nullptr);
  EnvRegistry& registry() { return registry_; }

  grpc::Status CreateEnv(grpc::ServerContext* context, const sim::v1::CreateEnvRequest* request,
                         sim::v1::CreateEnvResponse* response) override;
  grpc::Status Reset(grpc::ServerContext* context, const sim::v1::ResetRequest* request,
                     sim::v1::ResetResponse* response) override;
  grpc::Status Step(grpc::ServerContext* context, const sim::v1::StepRequest* request,
                    sim::v1::StepResponse* response) override;
  grpc::Status ComputeReward(grpc::ServerContext* context,
                             const sim::v1::ComputeRewardRequest* request,
                             sim::v1::ComputeRewardResponse* response) override;
  grpc::Status GetEnvSpec(grpc::ServerContext* context, const sim::v1::GetEnvSpecRequest* request,
                          sim::v1::GetEnvSpecResponse* response) override;
  grpc::Status CloseEnv(grpc::ServerContext* context, const sim::v1::CloseEnvRequest* request,
                        sim::v1::CloseEnvResponse* response) override;
  grpc::Status StreamRollout(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<sim::v1::StreamRolloutResponse, sim::v1::StreamRolloutRequest>*
          stream) override;

 private:
  void count_steps(const sim::v1::StepResponse& response);

  EnvRegistry registry_;
  Counter* env_steps_ = nullptr;
  StreamLimits* limits_ = nullptr;
};

// The core of Reset and Step, shared by the unary calls and the rollout stream.
void reset_batch(EnvBatch& batch, const sim::v1::ResetRequest& request,
                 sim::v1::ResetResponse& response);
void step_batch(EnvBatch& batch, const sim::v1::StepRequest& request,
                sim::v1::StepResponse& response);

}  // namespace pnp::services
