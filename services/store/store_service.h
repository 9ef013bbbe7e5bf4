#pragma once
// pnp.store.v1.StoreService over the platform's SQLite store: the one process that opens
// the file when the servers run on several machines. Each RPC is one store operation
// (store/store.h) on a pooled connection, with the store's own errors as canonical codes;
// checkpoint bytes are verified against their checksum on arrival; WatchPromotions streams
// the promotions whenever this service (or, within a second, anything else writing the
// file) changes them.

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <span>
#include <string>
#include <string_view>

#include "pnp/store/v1/store_service.grpc.pb.h"
#include "services/common/stream_limits.h"
#include "services/store/promotion_feed.h"
#include "services/store/store_connections.h"
#include "services/store/store_convert.h"
#include "services/store/transfer_budget.h"
#include "store/audit_trail.h"

namespace pnp::services {

// Checks a checkpoint's bytes as a replica would serve them for `role` (pnp-store-server
// passes rl::probe_checkpoint); throws pnp::Error naming `field`.
using CheckpointCheck = std::function<void(
    std::string_view role, std::span<const std::uint8_t> bytes, std::string_view field)>;

// pnp-store-server's --max-transfer-mb: four of the largest checkpoints it takes by default.
inline constexpr std::int64_t kDefaultMaxTransferBytes = 256LL << 20;

class StoreServiceImpl final : public store_v1::StoreService::Service {
 public:
  // `check` runs on every imported checkpoint before it is stored and on every checkpoint
  // before a promotion commits. `limits`: caps the streaming calls (watches and checkpoint
  // transfers; may be null). `quotas`: what a checkpoint, a run and a principal may hold
  // (store/store_quotas.h). `max_transfer_bytes`: checkpoint bytes held in memory for
  // transfers at once (transfer_budget.h).
  StoreServiceImpl(const std::string& path, CheckpointCheck check, StreamLimits* limits = nullptr,
                   store::DatabaseOptions options = {}, store::StoreQuotas quotas = {},
                   std::int64_t max_transfer_bytes = kDefaultMaxTransferBytes);
  // Ends the watch streams (call before the server shuts down).
  void stop_watches() { stopping_ = true; }

  grpc::Status CreateRun(grpc::ServerContext*, const store_v1::CreateRunRequest*,
                         store_v1::RunResponse*) override;
  grpc::Status GetRun(grpc::ServerContext*, const store_v1::GetRunRequest*,
                      store_v1::RunResponse*) override;
  grpc::Status ListRuns(grpc::ServerContext*, const store_v1::ListRunsRequest*,
                        store_v1::ListRunsResponse*) override;
  grpc::Status SetRunState(grpc::ServerContext*, const store_v1::SetRunStateRequest*,
                           store_v1::RunResponse*) override;
  grpc::Status ClaimNextRun(grpc::ServerContext*, const store_v1::ClaimNextRunRequest*,
                            store_v1::ClaimNextRunResponse*) override;
  grpc::Status RenewLease(grpc::ServerContext*, const store_v1::RenewLeaseRequest*,
                          store_v1::RenewLeaseResponse*) override;
  grpc::Status ReleaseRun(grpc::ServerContext*, const store_v1::ReleaseRunRequest*,
                          store_v1::ReleaseRunResponse*) override;
  grpc::Status AddRunWallTime(grpc::ServerContext*, const store_v1::AddRunWallTimeRequest*,
                              store_v1::RunResponse*) override;
  grpc::Status CountClaimable(grpc::ServerContext*, const store_v1::CountClaimableRequest*,
                              store_v1::CountClaimableResponse*) override;
  grpc::Status RecordMetric(grpc::ServerContext*, const store_v1::RecordMetricRequest*,
                            store_v1::RecordMetricResponse*) override;
  grpc::Status ListMetrics(grpc::ServerContext*, const store_v1::ListMetricsRequest*,
                           store_v1::ListMetricsResponse*) override;
  grpc::Status SaveCheckpoint(grpc::ServerContext*,
                              grpc::ServerReader<store_v1::SaveCheckpointRequest>*,
                              store_v1::CheckpointInfo*) override;
  grpc::Status LoadCheckpoint(grpc::ServerContext*, const store_v1::LoadCheckpointRequest*,
                              grpc::ServerWriter<store_v1::LoadCheckpointResponse>*) override;
  grpc::Status GetCheckpointInfo(grpc::ServerContext*, const store_v1::GetCheckpointInfoRequest*,
                                 store_v1::CheckpointInfo*) override;
  grpc::Status ListCheckpoints(grpc::ServerContext*, const store_v1::ListCheckpointsRequest*,
                               store_v1::ListCheckpointsResponse*) override;
  grpc::Status LatestCheckpoint(grpc::ServerContext*, const store_v1::LatestCheckpointRequest*,
                                store_v1::LatestCheckpointResponse*) override;
  grpc::Status ImportFinished(grpc::ServerContext*,
                              grpc::ServerReader<store_v1::ImportFinishedRequest>*,
                              store_v1::ImportFinishedResponse*) override;
  grpc::Status Promote(grpc::ServerContext*, const store_v1::PromoteRequest*,
                       store_v1::PromotionsResponse*) override;
  grpc::Status GetPromotion(grpc::ServerContext*, const store_v1::GetPromotionRequest*,
                            store_v1::GetPromotionResponse*) override;
  grpc::Status ListPromotions(grpc::ServerContext*, const store_v1::ListPromotionsRequest*,
                              store_v1::PromotionsResponse*) override;
  grpc::Status WatchPromotions(grpc::ServerContext*, const store_v1::WatchPromotionsRequest*,
                               grpc::ServerWriter<store_v1::PromotionsResponse>*) override;
  grpc::Status PruneCheckpoints(grpc::ServerContext*, const store_v1::PruneCheckpointsRequest*,
                                store_v1::GcReport*) override;
  grpc::Status CollectGarbage(grpc::ServerContext*, const store_v1::CollectGarbageRequest*,
                              store_v1::GcReport*) override;
  grpc::Status Backup(grpc::ServerContext*, const store_v1::BackupRequest*,
                      grpc::ServerWriter<store_v1::BackupResponse>*) override;
  grpc::Status AppendAudit(grpc::ServerContext*, const store_v1::AppendAuditRequest*,
                           store_v1::AppendAuditResponse*) override;
  grpc::Status ReadAudit(grpc::ServerContext*, const store_v1::ReadAuditRequest*,
                         store_v1::ReadAuditResponse*) override;

 private:
  StoreConnections connections_;
  store::StoreQuotas quotas_;
  CheckpointCheck check_;
  // Audit batches are committed before AppendAudit answers, one batch at a time.
  std::mutex audit_mutex_;
  store::AuditSink audit_sink_;
  StreamLimits* limits_;
  TransferBudget transfers_;
  std::mutex backup_mutex_;  // held by the one Backup being made
  PromotionFeed promotions_changed_;
  std::atomic<bool> stopping_{false};
};

}  // namespace pnp::services
