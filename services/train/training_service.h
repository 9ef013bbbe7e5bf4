#pragma once
// pnp.train.v1.TrainingService over a RunManager (core/training): requests are validated
// and converted here, the runs themselves live in the manager and the store.

#include <memory>

#include "pnp/train/v1/train_service.grpc.pb.h"
#include "services/common/stream_limits.h"
#include "training/run_manager.h"

namespace pnp::services {

class TrainingServiceImpl final : public train::v1::TrainingService::Service {
 public:
  // `limits` (null: none) bounds the watch streams; it must outlive the service.
  explicit TrainingServiceImpl(training::RunManager& manager, StreamLimits* limits = nullptr)
      : manager_(manager), limits_(limits) {}

  grpc::Status CreateTrainingRun(grpc::ServerContext* context,
                                 const train::v1::CreateTrainingRunRequest* request,
                                 train::v1::CreateTrainingRunResponse* response) override;
  grpc::Status GetTrainingRun(grpc::ServerContext* context,
                              const train::v1::GetTrainingRunRequest* request,
                              train::v1::GetTrainingRunResponse* response) override;
  grpc::Status ListTrainingRuns(grpc::ServerContext* context,
                                const train::v1::ListTrainingRunsRequest* request,
                                train::v1::ListTrainingRunsResponse* response) override;
  grpc::Status CancelTrainingRun(grpc::ServerContext* context,
                                 const train::v1::CancelTrainingRunRequest* request,
                                 train::v1::CancelTrainingRunResponse* response) override;
  grpc::Status WatchTrainingRun(
      grpc::ServerContext* context, const train::v1::WatchTrainingRunRequest* request,
      grpc::ServerWriter<train::v1::WatchTrainingRunResponse>* writer) override;
  grpc::Status GetRunMetrics(grpc::ServerContext* context,
                             const train::v1::GetRunMetricsRequest* request,
                             train::v1::GetRunMetricsResponse* response) override;
  grpc::Status ListCheckpoints(grpc::ServerContext* context,
                               const train::v1::ListCheckpointsRequest* request,
                               train::v1::ListCheckpointsResponse* response) override;

 private:
  void fill(const store::RunRecord& run, train::v1::TrainingRun& out);

  training::RunManager& manager_;
  StreamLimits* limits_;
};

}  // namespace pnp::services
