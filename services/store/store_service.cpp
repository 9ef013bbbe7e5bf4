#include "services/store/store_service.h"

#include <algorithm>
#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "common/checksum.h"
#include "common/error.h"
#include "services/common/access_control.h"
#include "services/common/convert.h"
#include "services/common/status.h"
#include "services/store/checkpoint_chunks.h"
#include "services/store/import_spool.h"
#include "services/store/store_convert.h"
#include "store/audit_trail.h"

namespace pnp::services {
namespace {

using std::chrono::milliseconds;

// A promotion written by another process on the same file reaches the watchers within this.
constexpr milliseconds kWatchRecheck{1000};
// How often a waiting watch looks at its caller (cancelled) and at shutdown.
constexpr milliseconds kWatchPoll{100};

void fill(const std::vector<store::Promotion>& promotions, store_v1::PromotionsResponse& out) {
  out.clear_promotions();
  for (const auto& p : promotions) to_proto(p, *out.add_promotions());
}

bool same(const std::vector<store::Promotion>& a, const std::vector<store::Promotion>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (a[k].role != b[k].role || a[k].checkpoint_id != b[k].checkpoint_id ||
        a[k].promoted_ms != b[k].promoted_ms)
      return false;
  }
  return true;
}

// One ImportFinished: a hierarchy (four roles) and the end-to-end baseline, with room; its
// blobs wait on disk (import_spool.h) until its one transaction commits.
constexpr std::size_t kMaxImportRuns = 8;
constexpr std::int64_t kMaxImportBytes = 256LL << 20;

// A client's idempotency key: room left in store::kMaxRequestIdBytes for the principal.
constexpr std::size_t kMaxClientRequestIdBytes = 384;

std::optional<long long> optional_steps(bool has, std::int64_t steps) {
  return has ? std::optional<long long>(steps) : std::nullopt;
}

// A run's owner is a server instance under the principal the store authenticated,
// "<principal>/<instance>": another principal cannot name it, whatever it reads from
// ListRuns. Without an auth policy, the instance as sent.
std::string owner_of(const grpc::ServerContext& context, const std::string& instance) {
  const std::string principal = principal_of(context);
  return principal.empty() || instance.empty() ? instance : principal + "/" + instance;
}

// Who a promotion is recorded as: the operator who called, or the operator a delegate
// server (pnp-inference) authenticated, as "<operator> via <server>". Without an auth
// policy, whoever the caller names.
std::string promoter(const grpc::ServerContext& context, const std::string& claimed) {
  const std::string principal = principal_of(context);
  if (principal.empty()) return claimed;
  if (caller_holds(context, security::AccessClass::kOperator)) {
    if (!claimed.empty() && claimed != principal) {
      throw_invalid_argument("promoted_by",
                             "empty or \"" + principal + "\" (an operator promotes as itself)",
                             "\"" + claimed + "\"");
    }
    return principal;
  }
  if (claimed.empty()) {
    throw_invalid_argument("promoted_by",
                           "the operator " + principal +
                               " authenticated and acts for (a server that promotes for "
                               "operators needs an --auth-policy of its own)",
                           "\"\"");
  }
  return claimed + " via " + principal;
}

}  // namespace

StoreServiceImpl::StoreServiceImpl(const std::string& path, CheckpointCheck check,
                                   StreamLimits* limits, store::DatabaseOptions options,
                                   store::StoreQuotas quotas, std::int64_t max_transfer_bytes)
    : connections_(path, options, quotas),
      quotas_(quotas),
      check_(std::move(check)),
      limits_(limits),
      transfers_(max_transfer_bytes, quotas.max_checkpoint_bytes) {
  if (!check_) throw_invalid_argument("check", "a checkpoint check", "none");
}

grpc::Status StoreServiceImpl::CreateRun(grpc::ServerContext* context,
                                         const store_v1::CreateRunRequest* request,
                                         store_v1::RunResponse* response) {
  return guarded([&] {
    if (request->request_id().size() > kMaxClientRequestIdBytes) {
      throw_invalid_argument("request_id",
                             "at most " + std::to_string(kMaxClientRequestIdBytes) + " bytes",
                             std::to_string(request->request_id().size()) + " bytes");
    }
    require_role(*context, request->spec().role(), "spec.role");
    // One principal's key never names another's run.
    const std::string key =
        request->request_id().empty() ? "" : owner_of(*context, request->request_id());
    to_proto(connections_.borrow()->create_run_for(from_proto(request->spec()), key,
                                                   principal_of(*context)),
             *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::GetRun(grpc::ServerContext*, const store_v1::GetRunRequest* request,
                                      store_v1::RunResponse* response) {
  return guarded([&] {
    to_proto(connections_.borrow()->get_run(request->run_id()), *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ListRuns(grpc::ServerContext*,
                                        const store_v1::ListRunsRequest* request,
                                        store_v1::ListRunsResponse* response) {
  return guarded([&] {
    for (const auto& run : connections_.borrow()->list_runs(from_proto(*request)))
      to_proto(run, *response->add_runs());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::SetRunState(grpc::ServerContext* context,
                                           const store_v1::SetRunStateRequest* request,
                                           store_v1::RunResponse* response) {
  return guarded([&] {
    const store::RunState state = store::parse_run_state(request->state(), "state");
    to_proto(connections_.borrow()->set_state(request->run_id(), state, request->error(),
                                              owner_of(*context, request->owner())),
             *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ClaimNextRun(grpc::ServerContext* context,
                                            const store_v1::ClaimNextRunRequest* request,
                                            store_v1::ClaimNextRunResponse* response) {
  return guarded([&] {
    require_role(*context, request->role(), "role");
    const auto lease = lease_from_proto(request->lease_ms(), "lease_ms");
    if (auto run = connections_.borrow()->claim_next(request->role(),
                                                     owner_of(*context, request->owner()), lease))
      to_proto(*run, *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::RenewLease(grpc::ServerContext* context,
                                          const store_v1::RenewLeaseRequest* request,
                                          store_v1::RenewLeaseResponse* response) {
  return guarded([&] {
    const auto lease = lease_from_proto(request->lease_ms(), "lease_ms");
    response->set_renewed(connections_.borrow()->renew_lease(
        request->run_id(), owner_of(*context, request->owner()), lease));
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ReleaseRun(grpc::ServerContext* context,
                                          const store_v1::ReleaseRunRequest* request,
                                          store_v1::ReleaseRunResponse*) {
  return guarded([&] {
    connections_.borrow()->release(request->run_id(), owner_of(*context, request->owner()));
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::AddRunWallTime(grpc::ServerContext* context,
                                              const store_v1::AddRunWallTimeRequest* request,
                                              store_v1::RunResponse* response) {
  return guarded([&] {
    to_proto(connections_.borrow()->add_wall_time(request->run_id(),
                                                  services::from_proto(request->part()),
                                                  owner_of(*context, request->owner())),
             *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::CountClaimable(grpc::ServerContext* context,
                                              const store_v1::CountClaimableRequest* request,
                                              store_v1::CountClaimableResponse* response) {
  return guarded([&] {
    require_role(*context, request->role(), "role");
    response->set_count(connections_.borrow()->count_claimable(
        request->role(), owner_of(*context, request->owner())));
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::RecordMetric(grpc::ServerContext* context,
                                            const store_v1::RecordMetricRequest* request,
                                            store_v1::RecordMetricResponse*) {
  return guarded([&] {
    connections_.borrow()->record_metric(
        request->run_id(), from_proto(request->point()), request->reached(),
        optional_steps(request->has_steps_to_target(), request->steps_to_target()),
        owner_of(*context, request->owner()));
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ListMetrics(grpc::ServerContext*,
                                           const store_v1::ListMetricsRequest* request,
                                           store_v1::ListMetricsResponse* response) {
  return guarded([&] {
    auto store = connections_.borrow();
    const auto points = request->has_after_env_steps()
                            ? store->metrics_after(request->run_id(), request->after_env_steps())
                            : store->metrics(request->run_id());
    for (const auto& p : points) to_proto(p, *response->add_points());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::SaveCheckpoint(
    grpc::ServerContext* context, grpc::ServerReader<store_v1::SaveCheckpointRequest>* reader,
    store_v1::CheckpointInfo* response) {
  return guarded([&] {
    auto slot = admit_stream(limits_, *context, "SaveCheckpoint");
    store_v1::SaveCheckpointRequest message;
    if (!reader->Read(&message) || !message.has_header()) {
      throw_invalid_argument("header", "a SaveCheckpointHeader as the first message",
                             "a stream without one");
    }
    const store_v1::SaveCheckpointHeader header = message.header();
    BlobAssembler blob("checkpoint of run " + std::to_string(header.run_id()), header.size_bytes(),
                       header.checksum(), "header.size_bytes", "header.checksum",
                       quotas_.max_checkpoint_bytes);
    const auto held = transfers_.reserve(*context, "SaveCheckpoint", header.size_bytes());
    while (reader->Read(&message)) {
      slot.touch();
      if (!message.has_chunk()) {
        throw_invalid_argument("chunk", "the blob's bytes after the header", "a second header");
      }
      blob.append(message.chunk());
    }
    const std::vector<std::uint8_t> bytes = blob.take();
    const std::string owner = owner_of(*context, header.owner());
    auto store = connections_.borrow();
    store::CheckpointInfo info;
    switch (header.kind_case()) {
      case store_v1::SaveCheckpointHeader::kEvaluated:
        info = store->save_checkpoint(header.run_id(), header.evaluated().env_steps(),
                                      header.evaluated().eval_success(), bytes, owner);
        break;
      case store_v1::SaveCheckpointHeader::kUnevaluated:
        info = store->save_unevaluated(header.run_id(), header.unevaluated().env_steps(),
                                       from_proto(header.unevaluated().counters()), bytes, owner);
        break;
      case store_v1::SaveCheckpointHeader::kEvaluation: {
        const auto& e = header.evaluation();
        info = store->record_evaluation(
            header.run_id(), from_proto(e.point()), bytes, e.reached(),
            optional_steps(e.has_steps_to_target(), e.steps_to_target()), owner);
        break;
      }
      default:
        throw_invalid_argument("header.kind", "evaluated, unevaluated or evaluation", "none");
    }
    to_proto(info, *response);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::LoadCheckpoint(
    grpc::ServerContext* context, const store_v1::LoadCheckpointRequest* request,
    grpc::ServerWriter<store_v1::LoadCheckpointResponse>* writer) {
  return guarded([&] {
    auto slot = admit_stream(limits_, *context, "LoadCheckpoint");
    const auto held = transfers_.reserve(
        *context, "LoadCheckpoint",
        connections_.borrow()->checkpoint_info(request->checkpoint_id()).size_bytes);
    const store::Checkpoint checkpoint = connections_.borrow()->load_checkpoint(
        request->checkpoint_id());  // verified against its checksum, or DATA_LOSS
    store_v1::LoadCheckpointResponse message;
    to_proto(checkpoint.info, *message.mutable_info());
    if (!writer->Write(message)) return grpc::Status(grpc::StatusCode::CANCELLED, "caller left");
    const bool sent = for_each_chunk(checkpoint.blob, [&](std::string_view chunk) {
      message.Clear();
      message.set_chunk(std::string(chunk));
      if (!writer->Write(message)) return false;
      slot.touch();
      return true;
    });
    return sent ? grpc::Status::OK : grpc::Status(grpc::StatusCode::CANCELLED, "caller left");
  });
}

grpc::Status StoreServiceImpl::GetCheckpointInfo(grpc::ServerContext*,
                                                 const store_v1::GetCheckpointInfoRequest* request,
                                                 store_v1::CheckpointInfo* response) {
  return guarded([&] {
    to_proto(connections_.borrow()->checkpoint_info(request->checkpoint_id()), *response);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ListCheckpoints(grpc::ServerContext*,
                                               const store_v1::ListCheckpointsRequest* request,
                                               store_v1::ListCheckpointsResponse* response) {
  return guarded([&] {
    for (const auto& info : connections_.borrow()->checkpoints(request->run_id()))
      to_proto(info, *response->add_checkpoints());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::LatestCheckpoint(grpc::ServerContext*,
                                                const store_v1::LatestCheckpointRequest* request,
                                                store_v1::LatestCheckpointResponse* response) {
  return guarded([&] {
    if (auto info = connections_.borrow()->latest_checkpoint(request->run_id()))
      to_proto(*info, *response->mutable_checkpoint());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ImportFinished(
    grpc::ServerContext* context, grpc::ServerReader<store_v1::ImportFinishedRequest>* reader,
    store_v1::ImportFinishedResponse* response) {
  return guarded([&] {
    auto slot = admit_stream(limits_, *context, "ImportFinished");
    // Each blob arrives whole (held against the transfer budget), is checked as a replica
    // would serve it, written to the spool and dropped; the one transaction that stores the
    // import reads them back one at a time.
    ImportSpool spool(connections_.path());
    std::vector<store::FinishedRun> runs;
    std::optional<BlobAssembler> blob;
    std::optional<TransferBudget::Reservation> held;
    std::int64_t largest = 0;
    bool promote = false;
    const auto finish_run = [&] {
      if (!blob) return;
      const std::string field = "runs[" + std::to_string(runs.size() - 1) + "]";
      const std::vector<std::uint8_t> bytes = blob->take();
      check_(runs.back().spec.role, bytes, field + ".checkpoint");
      const ImportSpool::Segment segment = spool.write(bytes);
      runs.back().read_blob = [&spool, segment] { return spool.read(segment); };
      largest = std::max(largest, segment.size);
      blob.reset();
      held.reset();
    };
    std::int64_t declared = 0;  // bounds the spool
    store_v1::ImportFinishedRequest message;
    while (reader->Read(&message)) {
      slot.touch();
      if (message.has_run()) {
        finish_run();
        const auto& run = message.run();
        const std::string field = "runs[" + std::to_string(runs.size()) + "]";
        if (runs.size() >= kMaxImportRuns) {
          throw_invalid_argument(
              "runs", "at most " + std::to_string(kMaxImportRuns) + " per import", "more");
        }
        if (runs.empty()) promote = run.promote();
        blob.emplace(field, run.size_bytes(), run.checksum(), field + ".size_bytes",
                     field + ".checksum", quotas_.max_checkpoint_bytes);
        if ((declared += run.size_bytes()) > kMaxImportBytes) {
          throw Error(ErrorCode::kResourceExhausted,
                      field + ".size_bytes: the import's checkpoints would pass the " +
                          std::to_string(kMaxImportBytes) +
                          " bytes one import may bring: import in several parts");
        }
        held.emplace(transfers_.reserve(*context, "ImportFinished", run.size_bytes()));
        runs.push_back({from_proto(run.spec()), {}});
      } else {
        if (!blob) throw_invalid_argument("run", "a run header before its chunks", "a chunk");
        blob->append(message.chunk());
      }
    }
    finish_run();
    const auto committing = transfers_.reserve(*context, "ImportFinished", largest);
    const auto ids = connections_.borrow()->import_finished(
        runs, promote, promote ? promoter(*context, "") : std::string());
    if (promote) promotions_changed_.bump();
    for (const auto id : ids) response->add_checkpoint_ids(id);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::Promote(grpc::ServerContext* context,
                                       const store_v1::PromoteRequest* request,
                                       store_v1::PromotionsResponse* response) {
  return guarded([&] {
    const std::string by = promoter(*context, request->promoted_by());
    const std::vector<std::int64_t> ids(request->checkpoint_ids().begin(),
                                        request->checkpoint_ids().end());
    // Every replica loads what is promoted, again at each restart: each checkpoint is
    // checked as a replica would serve it before the promotion commits.
    for (std::size_t i = 0; i < ids.size(); ++i) {
      auto store = connections_.borrow();
      const store::Checkpoint checkpoint = store->load_checkpoint(ids[i]);
      check_(store->get_run(checkpoint.info.run_id).spec.role, checkpoint.blob,
             "checkpoint_ids[" + std::to_string(i) + "] " + std::to_string(ids[i]));
    }
    const auto promoted = connections_.borrow()->promote(ids, by);
    promotions_changed_.bump();
    fill(promoted, *response);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::GetPromotion(grpc::ServerContext*,
                                            const store_v1::GetPromotionRequest* request,
                                            store_v1::GetPromotionResponse* response) {
  return guarded([&] {
    if (auto p = connections_.borrow()->promoted(request->role()))
      to_proto(*p, *response->mutable_promotion());
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ListPromotions(grpc::ServerContext*,
                                              const store_v1::ListPromotionsRequest*,
                                              store_v1::PromotionsResponse* response) {
  return guarded([&] {
    fill(connections_.borrow()->promotions(), *response);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::WatchPromotions(
    grpc::ServerContext* context, const store_v1::WatchPromotionsRequest*,
    grpc::ServerWriter<store_v1::PromotionsResponse>* writer) {
  return guarded([&] {
    auto slot = admit_stream(limits_, *context, "WatchPromotions");
    std::uint64_t seen = promotions_changed_.version();
    std::vector<store::Promotion> sent = connections_.borrow()->promotions();
    store_v1::PromotionsResponse message;
    fill(sent, message);
    if (!writer->Write(message)) return grpc::Status(grpc::StatusCode::CANCELLED, "caller left");
    slot.touch();
    auto last_read = std::chrono::steady_clock::now();
    auto last_write = last_read;
    while (!context->IsCancelled() && !stopping_) {
      const std::uint64_t now_seen = promotions_changed_.wait_past(seen, kWatchPoll);
      const auto now = std::chrono::steady_clock::now();
      bool changed = false;
      if (now_seen != seen || now - last_read >= kWatchRecheck) {
        seen = now_seen;
        last_read = now;
        auto current = connections_.borrow()->promotions();
        changed = !same(current, sent);
        if (changed) sent = std::move(current);
      }
      if (!changed && now - last_write < slot.heartbeat_interval()) continue;
      if (changed) fill(sent, message);
      message.set_heartbeat(!changed);  // else the same set, to show the watch is alive
      if (!writer->Write(message)) break;
      last_write = std::chrono::steady_clock::now();
      slot.touch();
    }
    return stopping_ ? grpc::Status(grpc::StatusCode::UNAVAILABLE, "the store server is stopping")
                     : grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::PruneCheckpoints(grpc::ServerContext*,
                                                const store_v1::PruneCheckpointsRequest* request,
                                                store_v1::GcReport* response) {
  return guarded([&] {
    const auto policy = retention_from_proto(request->keep_last(), "keep_last");
    to_proto(connections_.borrow()->prune_checkpoints(request->run_id(), policy), *response);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::CollectGarbage(grpc::ServerContext*,
                                              const store_v1::CollectGarbageRequest* request,
                                              store_v1::GcReport* response) {
  return guarded([&] {
    const auto policy = retention_from_proto(request->keep_last(), "keep_last");
    to_proto(connections_.borrow()->collect_garbage(policy), *response);
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::Backup(grpc::ServerContext* context, const store_v1::BackupRequest*,
                                      grpc::ServerWriter<store_v1::BackupResponse>* writer) {
  return guarded([&] {
    auto slot = admit_stream(limits_, *context, "Backup");
    // One at a time: each is a whole copy of the store on its volume.
    const std::unique_lock one_backup(backup_mutex_, std::try_to_lock);
    if (!one_backup.owns_lock()) {
      throw Error(ErrorCode::kResourceExhausted,
                  "Backup: another backup is being made on this store server; retry when it ends");
    }
    // The copy is made beside the store (same file system, so it costs no network and the
    // disk is one the operator already sizes) and removed once sent.
    const std::string copy =
        connections_.path() + ".backup-" +
        std::to_string(std::chrono::steady_clock::now().time_since_epoch().count());
    const store::BackupReport report = connections_.borrow()->backup(copy);
    const TemporaryFile remove_when_done(copy);
    store_v1::BackupResponse message;
    auto& info = *message.mutable_info();
    info.set_size_bytes(report.bytes);
    info.set_checksum(checksum_hex(file_checksum(copy)));
    info.set_runs(report.runs);
    info.set_checkpoints(report.checkpoints);
    if (!writer->Write(message)) return grpc::Status(grpc::StatusCode::CANCELLED, "caller left");
    const bool sent = for_each_file_chunk(copy, [&](std::string_view chunk) {
      message.Clear();
      message.set_chunk(std::string(chunk));
      if (context->IsCancelled() || !writer->Write(message)) return false;
      slot.touch();
      return true;
    });
    return sent ? grpc::Status::OK : grpc::Status(grpc::StatusCode::CANCELLED, "caller left");
  });
}

namespace {

// What one AppendAudit may carry: a client batches at most 256 records of a few KB each.
constexpr int kMaxAuditRecords = 1000;
constexpr std::size_t kMaxAuditRequestBytes = 4096;  // the recorded JSON is cut at 2 KB
constexpr std::size_t kMaxAuditFieldBytes = 512;
constexpr int kMaxAuditRead = 10'000;
// A page of ReadAudit: well under the store service's 512 KiB message cap.
constexpr std::size_t kAuditPageBytes = 256 << 10;

void validate(const store_v1::AuditEntry& entry, int index) {
  const std::string where = "records[" + std::to_string(index) + "].";
  if (entry.ts_ms() <= 0)
    throw_invalid_argument(where + "ts_ms", "a time after the epoch",
                           std::to_string(entry.ts_ms()));
  if (entry.rpc().empty() || entry.code().empty())
    throw_invalid_argument(where + "rpc and code", "both set", "an empty one");
  if (entry.request().size() > kMaxAuditRequestBytes)
    throw_invalid_argument(where + "request", "at most 4096 bytes",
                           std::to_string(entry.request().size()) + " bytes");
  for (const std::string* field :
       {&entry.service(), &entry.principal(), &entry.peer(), &entry.rpc(), &entry.code()}) {
    if (field->size() > kMaxAuditFieldBytes)
      throw_invalid_argument(where + "service, principal, peer, rpc, code", "at most 512 bytes",
                             std::to_string(field->size()) + " bytes");
  }
}

}  // namespace

grpc::Status StoreServiceImpl::AppendAudit(grpc::ServerContext* context,
                                           const store_v1::AppendAuditRequest* request,
                                           store_v1::AppendAuditResponse*) {
  return guarded([&] {
    if (request->records_size() > kMaxAuditRecords) {
      throw_invalid_argument("records", "at most 1000 per call",
                             std::to_string(request->records_size()));
    }
    // The batch is signed by the server that sent it, as the store authenticated it: a
    // record names both who the sender says called and who wrote it here, and when.
    const std::string principal = principal_of(*context);
    const std::string recorded_by = principal.empty() ? "peer:" + context->peer() : principal;
    const store::Millis received_ms = store::now_ms();
    std::vector<store::AuditRecord> batch;
    for (int k = 0; k < request->records_size(); ++k) {
      validate(request->records(k), k);
      batch.push_back(from_proto(request->records(k)));
      batch.back().recorded_by = recorded_by;
      batch.back().received_ms = received_ms;
    }
    if (batch.empty()) return grpc::Status::OK;
    const std::lock_guard lock(audit_mutex_);
    if (!audit_sink_) audit_sink_ = store::file_audit_sink(connections_.path())();
    try {
      audit_sink_(batch);
    } catch (...) {
      audit_sink_ = nullptr;  // opened afresh for the next batch
      throw;
    }
    return grpc::Status::OK;
  });
}

grpc::Status StoreServiceImpl::ReadAudit(grpc::ServerContext*,
                                         const store_v1::ReadAuditRequest* request,
                                         store_v1::ReadAuditResponse* response) {
  return guarded([&] {
    if (request->limit() < 1 || request->limit() > kMaxAuditRead)
      throw_invalid_argument("limit", "1..10000", std::to_string(request->limit()));
    if (request->before_id() < 0)
      throw_invalid_argument("before_id", "0 or a record id", std::to_string(request->before_id()));
    const auto records = store::read_audit(connections_.path(), request->since_ms(),
                                           request->limit(), request->before_id());
    // The newest records that fit one message; the older rest is the next page.
    std::size_t first = records.size(), bytes = 0;
    while (first > 0) {
      store_v1::AuditEntry entry;
      to_proto(records[first - 1], entry);
      bytes += entry.ByteSizeLong() + 8;  // with the field's tag and length
      if (bytes > kAuditPageBytes) break;
      --first;
    }
    for (std::size_t k = first; k < records.size(); ++k)
      to_proto(records[k], *response->add_records());
    response->set_more(first > 0);
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
