#pragma once
// pnp.policy.v1.PolicyService over the store's promoted checkpoints: Predict and
// PredictSession answer with a HierarchyController borrowed from the served hierarchy;
// a promotion (through this service or any other writer of the store) is picked up by a
// reload that swaps the served hierarchy atomically: requests in flight and open sessions
// finish on the one they started with, new ones get the new one, none is dropped.

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "serving/served_hierarchy.h"
#include "store/run_store.h"

namespace pnp::services {

class PolicyServiceImpl final : public policy::v1::PolicyService::Service {
 public:
  explicit PolicyServiceImpl(const std::string& db_path);

  // Loads the promoted checkpoints if they differ from the served ones; returns whether
  // the hierarchy changed. A failure keeps the current one and is rethrown.
  bool reload();
  bool ready() const { return served_.load() != nullptr; }
  // The served hierarchy's batching counters per expert (zeros when nothing is served).
  std::array<serving::BatchStats, sim::kNumSubtasks> batch_stats() const;

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
  std::shared_ptr<const serving::ServedHierarchy> served_or_unavailable() const;

  std::mutex store_mutex_;  // the connection is used by one thread at a time
  store::RunStore store_;
  std::atomic<std::shared_ptr<const serving::ServedHierarchy>> served_;
};

}  // namespace pnp::services
