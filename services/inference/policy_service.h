#pragma once
// pnp.policy.v1.PolicyService over the store's promoted checkpoints: Predict and
// PredictSession answer with a controller borrowed from the served policy, either the
// hierarchy (choreographer + experts) or the end-to-end baseline (the promoted e2e
// actor; its answers name no subtask: SUBTASK_UNSPECIFIED, no probabilities, the e2e
// checkpoint as expert, choreographer 0). A promotion (through this service or any other
// writer of the store) of a role the served policy uses is picked up by a reload that
// swaps it atomically: requests in flight and open sessions finish on the one they
// started with, new ones get the new one, none is dropped.

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/shared_snapshot.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "services/common/metrics_registry.h"
#include "services/common/stream_limits.h"
#include "serving/served_policy.h"
#include "store/store.h"

namespace pnp::services {

class PolicyServiceImpl final : public policy::v1::PolicyService::Service {
 public:
  // `limits` (null: none) bounds the PredictSession streams; `metrics` (null: none) gets
  // pnp_inference_session_step_seconds, each session answer's time in the server (a
  // session's own RPC duration is the whole episode's). Both must outlive the service.
  // Serves the store file at `db_path`, read in this process.
  explicit PolicyServiceImpl(const std::string& db_path,
                             serving::PolicyKind kind = serving::PolicyKind::kHierarchy,
                             StreamLimits* limits = nullptr, MetricsRegistry* metrics = nullptr);
  // Serves the store `open_store` opens (pnp-store-server: remote_store_opener); one handle
  // reads, another is opened at the first promotion.
  PolicyServiceImpl(store::StoreOpener open_store, serving::PolicyKind kind,
                    StreamLimits* limits = nullptr, MetricsRegistry* metrics = nullptr);

  // Loads the promoted checkpoints of the served kind if they differ from the served
  // ones; returns whether the policy changed. A failure keeps the current one and is
  // rethrown.
  bool reload();
  bool ready() const { return served_.load() != nullptr; }
  serving::PolicyKind kind() const { return kind_; }
  // The served policy's batching counters per batched actor, in
  // serving::batched_actors(kind()) order (zeros when nothing is served).
  std::vector<serving::BatchStats> batch_stats() const;

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
  std::shared_ptr<const serving::ServedPolicy> served_or_unavailable();

  PolicyServiceImpl(store::StoreOpener open_reader, store::StoreOpener open_writer,
                    serving::PolicyKind kind, StreamLimits* limits, MetricsRegistry* metrics);

  const serving::PolicyKind kind_;
  const store::StoreOpener open_writer_;
  StreamLimits* const limits_;
  Histogram* const session_step_seconds_;  // null: not recorded
  std::mutex store_mutex_;  // guards both connections: each is used by one thread at a time
  std::unique_ptr<store::Store> store_;   // serving's reads (read-only on a local file)
  std::unique_ptr<store::Store> writer_;  // opened at the first promotion
  std::string load_error_;  // why the last load failed (empty: it did not); store_mutex_
  SharedSnapshot<serving::ServedPolicy> served_;
};

}  // namespace pnp::services
