#include "services/store/remote_store.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "common/checksum.h"
#include "common/error.h"
#include "services/common/address.h"
#include "services/common/convert.h"
#include "services/common/status.h"
#include "services/store/checkpoint_chunks.h"
#include "services/store/store_convert.h"

namespace pnp::services {
namespace {

// gRPC retries the reads (and the lease renewal, which sets an absolute expiry) when the
// store server is unreachable or restarting; never a write that may have landed.
constexpr const char* kServiceConfig = R"({
  "methodConfig": [{
    "name": [
      {"service": "pnp.store.v1.StoreService", "method": "GetRun"},
      {"service": "pnp.store.v1.StoreService", "method": "ListRuns"},
      {"service": "pnp.store.v1.StoreService", "method": "CountClaimable"},
      {"service": "pnp.store.v1.StoreService", "method": "RenewLease"},
      {"service": "pnp.store.v1.StoreService", "method": "ListMetrics"},
      {"service": "pnp.store.v1.StoreService", "method": "LoadCheckpoint"},
      {"service": "pnp.store.v1.StoreService", "method": "GetCheckpointInfo"},
      {"service": "pnp.store.v1.StoreService", "method": "ListCheckpoints"},
      {"service": "pnp.store.v1.StoreService", "method": "LatestCheckpoint"},
      {"service": "pnp.store.v1.StoreService", "method": "GetPromotion"},
      {"service": "pnp.store.v1.StoreService", "method": "ListPromotions"},
      {"service": "pnp.store.v1.StoreService", "method": "ReadAudit"}
    ],
    "retryPolicy": {
      "maxAttempts": 4,
      "initialBackoff": "0.05s",
      "maxBackoff": "1s",
      "backoffMultiplier": 2,
      "retryableStatusCodes": ["UNAVAILABLE"]
    }
  }]
})";

std::vector<store::Promotion> promotions_from(const store_v1::PromotionsResponse& response) {
  std::vector<store::Promotion> out;
  for (const auto& p : response.promotions()) out.push_back(from_proto(p));
  return out;
}

}  // namespace

grpc::ChannelArguments store_channel_arguments() {
  grpc::ChannelArguments args;
  args.SetServiceConfigJSON(kServiceConfig);
  args.SetMaxReceiveMessageSize(kStoreMessageBytes);
  args.SetInt("grpc.http2.lookahead_bytes", 8 << 20);
  return args;
}

std::shared_ptr<grpc::Channel> dial_store(const std::string& address, const ClientTlsFiles& tls) {
  validate_address(address, "--store");  // the flag every caller takes it from
  return dial(address, tls, store_channel_arguments());
}

store::StoreOpener remote_store_opener(const std::string& address, const ClientTlsFiles& tls,
                                       RemoteStoreOptions options) {
  std::shared_ptr<grpc::Channel> channel = dial_store(address, tls);
  return [channel, address, options]() -> std::unique_ptr<store::Store> {
    return std::make_unique<RemoteStore>(channel, address, options);
  };
}

RemoteStore::RemoteStore(std::shared_ptr<grpc::Channel> channel, std::string address,
                         RemoteStoreOptions options)
    : stub_(store_v1::StoreService::NewStub(std::move(channel))),
      address_(std::move(address)),
      options_(options) {}

std::unique_ptr<grpc::ClientContext> RemoteStore::context(std::chrono::milliseconds timeout) const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + timeout);
  return context;
}

store::RunRecord RemoteStore::create_run(const store::RunSpec& spec,
                                         const std::string& request_id) {
  store_v1::CreateRunRequest request;
  to_proto(spec, *request.mutable_spec());
  request.set_request_id(request_id);
  const auto response = call(&store_v1::StoreService::Stub::CreateRun, request, "store CreateRun");
  return from_proto(response.run());
}

store::RunRecord RemoteStore::get_run(std::int64_t id) {
  store_v1::GetRunRequest request;
  request.set_run_id(id);
  const auto response = call(&store_v1::StoreService::Stub::GetRun, request, "store GetRun");
  return from_proto(response.run());
}

std::vector<store::RunRecord> RemoteStore::list_runs(const store::RunFilter& filter) {
  store_v1::ListRunsRequest request;
  to_proto(filter, request);
  const auto response = call(&store_v1::StoreService::Stub::ListRuns, request, "store ListRuns");
  std::vector<store::RunRecord> out;
  for (const auto& run : response.runs()) out.push_back(from_proto(run));
  return out;
}

store::RunRecord RemoteStore::set_state(std::int64_t id, store::RunState state,
                                        const std::string& error, const std::string& owner) {
  store_v1::SetRunStateRequest request;
  request.set_run_id(id);
  request.set_state(std::string(store::run_state_name(state)));
  request.set_error(error);
  request.set_owner(owner);
  const auto response =
      call(&store_v1::StoreService::Stub::SetRunState, request, "store SetRunState");
  return from_proto(response.run());
}

std::optional<store::RunRecord> RemoteStore::claim_next(const std::string& role,
                                                        const std::string& owner,
                                                        std::chrono::milliseconds lease) {
  store_v1::ClaimNextRunRequest request;
  request.set_role(role);
  request.set_owner(owner);
  request.set_lease_ms(lease.count());
  const auto response =
      call(&store_v1::StoreService::Stub::ClaimNextRun, request, "store ClaimNextRun");
  if (!response.has_run()) return std::nullopt;
  return from_proto(response.run());
}

bool RemoteStore::renew_lease(std::int64_t run_id, const std::string& owner,
                              std::chrono::milliseconds lease) {
  store_v1::RenewLeaseRequest request;
  request.set_run_id(run_id);
  request.set_owner(owner);
  request.set_lease_ms(lease.count());
  const auto response =
      call(&store_v1::StoreService::Stub::RenewLease, request, "store RenewLease");
  return response.renewed();
}

store::RunRecord RemoteStore::add_wall_time(std::int64_t run_id, const WallBreakdown& part,
                                            const std::string& owner) {
  store_v1::AddRunWallTimeRequest request;
  request.set_run_id(run_id);
  services::to_proto(part, *request.mutable_part());
  request.set_owner(owner);
  return from_proto(
      call(&store_v1::StoreService::Stub::AddRunWallTime, request, "store AddRunWallTime").run());
}

void RemoteStore::release(std::int64_t run_id, const std::string& owner) {
  store_v1::ReleaseRunRequest request;
  request.set_run_id(run_id);
  request.set_owner(owner);
  const auto response =
      call(&store_v1::StoreService::Stub::ReleaseRun, request, "store ReleaseRun");
}

std::int64_t RemoteStore::count_claimable(const std::string& role, const std::string& owner) {
  store_v1::CountClaimableRequest request;
  request.set_role(role);
  request.set_owner(owner);
  const auto response =
      call(&store_v1::StoreService::Stub::CountClaimable, request, "store CountClaimable");
  return response.count();
}

void RemoteStore::record_metric(std::int64_t run_id, const store::MetricPoint& point, bool reached,
                                std::optional<long long> steps_to_target,
                                const std::string& owner) {
  store_v1::RecordMetricRequest request;
  request.set_run_id(run_id);
  to_proto(point, *request.mutable_point());
  request.set_reached(reached);
  if (steps_to_target) request.set_steps_to_target(*steps_to_target);
  request.set_owner(owner);
  const auto response =
      call(&store_v1::StoreService::Stub::RecordMetric, request, "store RecordMetric");
}

std::vector<store::MetricPoint> RemoteStore::metrics(std::int64_t run_id) {
  return list_metrics(run_id, std::nullopt);
}

std::vector<store::MetricPoint> RemoteStore::metrics_after(std::int64_t run_id,
                                                           long long after_env_steps) {
  return list_metrics(run_id, after_env_steps);
}

std::vector<store::MetricPoint> RemoteStore::list_metrics(std::int64_t run_id,
                                                          std::optional<long long> after) {
  store_v1::ListMetricsRequest request;
  request.set_run_id(run_id);
  if (after) request.set_after_env_steps(*after);
  const auto response =
      call(&store_v1::StoreService::Stub::ListMetrics, request, "store ListMetrics");
  std::vector<store::MetricPoint> out;
  for (const auto& p : response.points()) out.push_back(from_proto(p));
  return out;
}

store::CheckpointInfo RemoteStore::save(const store_v1::SaveCheckpointHeader& header,
                                        std::span<const std::uint8_t> blob, std::string_view what) {
  auto ctx = context(options_.transfer_timeout);
  store_v1::CheckpointInfo response;
  auto writer = stub_->SaveCheckpoint(ctx.get(), &response);
  store_v1::SaveCheckpointRequest message;
  *message.mutable_header() = header;
  message.mutable_header()->set_checksum(fnv1a64_hex(blob));
  message.mutable_header()->set_size_bytes(static_cast<std::int64_t>(blob.size()));
  // A refused header ends the stream early: Finish() then carries the server's reason.
  if (writer->Write(message)) {
    for_each_chunk(blob, [&](std::string_view chunk) {
      message.Clear();
      message.set_chunk(std::string(chunk));
      return writer->Write(message);
    });
  }
  writer->WritesDone();
  throw_if_error(writer->Finish(), what, address_);
  return from_proto(response);
}

store::CheckpointInfo RemoteStore::save_checkpoint(std::int64_t run_id, long long env_steps,
                                                   double eval_success,
                                                   std::span<const std::uint8_t> blob,
                                                   const std::string& owner) {
  store_v1::SaveCheckpointHeader header;
  header.set_run_id(run_id);
  header.set_owner(owner);
  header.mutable_evaluated()->set_env_steps(env_steps);
  header.mutable_evaluated()->set_eval_success(eval_success);
  return save(header, blob, "store SaveCheckpoint");
}

store::CheckpointInfo RemoteStore::save_unevaluated(std::int64_t run_id, long long env_steps,
                                                    const store::TrainerCounters& counters,
                                                    std::span<const std::uint8_t> blob,
                                                    const std::string& owner) {
  store_v1::SaveCheckpointHeader header;
  header.set_run_id(run_id);
  header.set_owner(owner);
  header.mutable_unevaluated()->set_env_steps(env_steps);
  to_proto(counters, *header.mutable_unevaluated()->mutable_counters());
  return save(header, blob, "store SaveCheckpoint (unevaluated)");
}

store::CheckpointInfo RemoteStore::record_evaluation(
    std::int64_t run_id, const store::MetricPoint& point, std::span<const std::uint8_t> blob,
    bool reached, std::optional<long long> steps_to_target, const std::string& owner) {
  store_v1::SaveCheckpointHeader header;
  header.set_run_id(run_id);
  header.set_owner(owner);
  auto& evaluation = *header.mutable_evaluation();
  to_proto(point, *evaluation.mutable_point());
  evaluation.set_reached(reached);
  if (steps_to_target) evaluation.set_steps_to_target(*steps_to_target);
  return save(header, blob, "store SaveCheckpoint (evaluation)");
}

store::Checkpoint RemoteStore::load_checkpoint(std::int64_t checkpoint_id) {
  auto ctx = context(options_.transfer_timeout);
  store_v1::LoadCheckpointRequest request;
  request.set_checkpoint_id(checkpoint_id);
  auto reader = stub_->LoadCheckpoint(ctx.get(), request);
  store::Checkpoint checkpoint;
  std::optional<BlobAssembler> blob;
  store_v1::LoadCheckpointResponse message;
  const std::string what =
      "checkpoint " + std::to_string(checkpoint_id) + " from the store " + address_;
  while (reader->Read(&message)) {
    if (message.has_info()) {
      checkpoint.info = from_proto(message.info());
      blob.emplace(what, checkpoint.info.size_bytes, checkpoint.info.checksum, "info.size_bytes",
                   "info.checksum");
    } else if (blob) {
      blob->append(message.chunk());
    } else {
      throw Error(ErrorCode::kDataLoss, what + ": bytes arrived before the checkpoint's info");
    }
  }
  throw_if_error(reader->Finish(), "store LoadCheckpoint", address_);
  if (!blob) throw Error(ErrorCode::kDataLoss, what + ": the stream ended without the info");
  checkpoint.blob = blob->take();  // verified: size and checksum
  return checkpoint;
}

std::optional<store::CheckpointInfo> RemoteStore::latest_checkpoint(std::int64_t run_id) {
  store_v1::LatestCheckpointRequest request;
  request.set_run_id(run_id);
  const auto response =
      call(&store_v1::StoreService::Stub::LatestCheckpoint, request, "store LatestCheckpoint");
  if (!response.has_checkpoint()) return std::nullopt;
  return from_proto(response.checkpoint());
}

std::vector<store::CheckpointInfo> RemoteStore::checkpoints(std::int64_t run_id) {
  store_v1::ListCheckpointsRequest request;
  request.set_run_id(run_id);
  const auto response =
      call(&store_v1::StoreService::Stub::ListCheckpoints, request, "store ListCheckpoints");
  std::vector<store::CheckpointInfo> out;
  for (const auto& info : response.checkpoints()) out.push_back(from_proto(info));
  return out;
}

store::CheckpointInfo RemoteStore::checkpoint_info(std::int64_t checkpoint_id) {
  store_v1::GetCheckpointInfoRequest request;
  request.set_checkpoint_id(checkpoint_id);
  const auto response =
      call(&store_v1::StoreService::Stub::GetCheckpointInfo, request, "store GetCheckpointInfo");
  return from_proto(response);
}

std::vector<std::int64_t> RemoteStore::import_finished(std::span<const store::FinishedRun> runs,
                                                       bool promote, const std::string&) {
  auto ctx = context(options_.transfer_timeout);
  store_v1::ImportFinishedResponse response;
  auto writer = stub_->ImportFinished(ctx.get(), &response);
  store_v1::ImportFinishedRequest message;
  bool open = true;
  for (const auto& run : runs) {
    if (!open) break;
    message.Clear();
    std::vector<std::uint8_t> scratch;
    const auto& blob = run.bytes(scratch);
    auto& header = *message.mutable_run();
    to_proto(run.spec, *header.mutable_spec());
    header.set_checksum(fnv1a64_hex(blob));
    header.set_size_bytes(static_cast<std::int64_t>(blob.size()));
    header.set_promote(promote);
    open = writer->Write(message) && for_each_chunk(blob, [&](std::string_view chunk) {
             message.Clear();
             message.set_chunk(std::string(chunk));
             return writer->Write(message);
           });
  }
  writer->WritesDone();
  throw_if_error(writer->Finish(), "store ImportFinished", address_);
  return {response.checkpoint_ids().begin(), response.checkpoint_ids().end()};
}

std::vector<store::Promotion> RemoteStore::promote(std::span<const std::int64_t> checkpoint_ids,
                                                   const std::string& by) {
  store_v1::PromoteRequest request;
  for (const auto id : checkpoint_ids) request.add_checkpoint_ids(id);
  request.set_promoted_by(by);
  const auto response = call(&store_v1::StoreService::Stub::Promote, request, "store Promote");
  return promotions_from(response);
}

std::optional<store::Promotion> RemoteStore::promoted(const std::string& role) {
  store_v1::GetPromotionRequest request;
  request.set_role(role);
  const auto response =
      call(&store_v1::StoreService::Stub::GetPromotion, request, "store GetPromotion");
  if (!response.has_promotion()) return std::nullopt;
  return from_proto(response.promotion());
}

std::vector<store::Promotion> RemoteStore::promotions() {
  store_v1::ListPromotionsRequest request;
  const auto response =
      call(&store_v1::StoreService::Stub::ListPromotions, request, "store ListPromotions");
  return promotions_from(response);
}

store::GcReport RemoteStore::prune_checkpoints(std::int64_t run_id,
                                               const store::RetentionPolicy& policy) {
  store_v1::PruneCheckpointsRequest request;
  request.set_run_id(run_id);
  request.set_keep_last(policy.keep_last);
  const auto response = call(&store_v1::StoreService::Stub::PruneCheckpoints, request,
                             "store PruneCheckpoints", options_.transfer_timeout);
  return from_proto(response);
}

store::GcReport RemoteStore::collect_garbage(const store::RetentionPolicy& policy) {
  store_v1::CollectGarbageRequest request;
  request.set_keep_last(policy.keep_last);
  const auto response = call(&store_v1::StoreService::Stub::CollectGarbage, request,
                             "store CollectGarbage", options_.transfer_timeout);
  return from_proto(response);
}

store::BackupReport RemoteStore::backup(const std::string& destination) {
  if (std::filesystem::exists(destination)) {
    throw Error(ErrorCode::kFailedPrecondition,
                "backup: " + destination + " already exists (a backup never overwrites a file)");
  }
  const std::string partial = destination + ".partial";
  const TemporaryFile remove_unless_renamed(partial);
  std::ofstream out(partial, std::ios::binary | std::ios::trunc);
  if (!out) throw Error(ErrorCode::kFailedPrecondition, "backup: cannot write " + partial);
  auto ctx = context(options_.transfer_timeout);
  auto reader = stub_->Backup(ctx.get(), store_v1::BackupRequest());
  store_v1::BackupResponse message;
  std::optional<store_v1::BackupInfo> info;
  std::uint64_t checksum = kFnv1a64Start;
  std::int64_t received = 0;
  while (reader->Read(&message)) {
    if (message.has_info()) {
      info = message.info();
      continue;
    }
    const std::string& chunk = message.chunk();
    checksum = fnv1a64(std::span(reinterpret_cast<const std::uint8_t*>(chunk.data()), chunk.size()),
                       checksum);
    received += static_cast<std::int64_t>(chunk.size());
    out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
  }
  throw_if_error(reader->Finish(), "store Backup", address_);
  out.close();
  if (!out) throw Error(ErrorCode::kResourceExhausted, "backup: writing " + partial + " failed");
  const std::string what = "backup from the store " + address_;
  if (!info) throw Error(ErrorCode::kDataLoss, what + ": the stream ended without its info");
  if (received != info->size_bytes() || checksum_hex(checksum) != info->checksum()) {
    throw Error(ErrorCode::kDataLoss, what + ": " + std::to_string(received) +
                                          " bytes with checksum " + checksum_hex(checksum) +
                                          " arrived, not " + std::to_string(info->size_bytes()) +
                                          " with " + info->checksum());
  }
  std::filesystem::rename(partial, destination);
  return {destination, received, info->runs(), info->checkpoints()};
}

grpc::Status RemoteStore::watch_promotions(
    grpc::ClientContext& context,
    const std::function<bool(std::vector<store::Promotion>)>& on_change) {
  auto reader = stub_->WatchPromotions(&context, store_v1::WatchPromotionsRequest());
  store_v1::PromotionsResponse message;
  while (reader->Read(&message)) {
    if (message.heartbeat()) continue;  // nothing changed
    if (!on_change(promotions_from(message))) {
      context.TryCancel();
      break;
    }
  }
  return reader->Finish();
}

}  // namespace pnp::services
