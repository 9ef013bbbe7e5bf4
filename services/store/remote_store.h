#pragma once
// The store through pnp-store-server: the Store contract (store/store.h) for a server that
// does not open the SQLite file itself. Every error is the store's own, as the service
// returned it (NOT_FOUND, ABORTED, DATA_LOSS...), with a lost or slow store server
// UNAVAILABLE; checkpoint bytes are verified against their checksum on arrival.
//
// Reads are retried by gRPC on UNAVAILABLE (store_channel_arguments); writes are not (a
// write that may have landed is for its caller to judge: store/retry.h).

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "pnp/store/v1/store_service.grpc.pb.h"
#include "services/common/status.h"
#include "services/common/transport_security.h"
#include "services/store/store_convert.h"
#include "store/store.h"

namespace pnp::services {

struct RemoteStoreOptions {
  std::chrono::milliseconds call_timeout{10'000};       // one record, list or lease call
  std::chrono::milliseconds transfer_timeout{120'000};  // a checkpoint's bytes, an import
};

// Channel arguments for the store service: gRPC retries of its read calls (UNAVAILABLE,
// up to 4 attempts with backoff) and a message cap that fits a checkpoint chunk.
grpc::ChannelArguments store_channel_arguments();

// A channel to the store server at `address` (validated, named --store in errors), dialled
// with `tls` and store_channel_arguments().
std::shared_ptr<grpc::Channel> dial_store(const std::string& address, const ClientTlsFiles& tls);

// Opens RemoteStores that share one channel to the store server at `address`, dialled with
// `tls` (plaintext when it names no CA). Validates the address and files here.
store::StoreOpener remote_store_opener(const std::string& address, const ClientTlsFiles& tls,
                                       RemoteStoreOptions options = {});

class RemoteStore final : public store::Store {
 public:
  // `address` names the store server in errors.
  RemoteStore(std::shared_ptr<grpc::Channel> channel, std::string address,
              RemoteStoreOptions options = {});

  store::RunRecord create_run(const store::RunSpec& spec,
                              const std::string& request_id = "") override;
  store::RunRecord get_run(std::int64_t id) override;
  std::vector<store::RunRecord> list_runs(const store::RunFilter& filter = {}) override;
  store::RunRecord set_state(std::int64_t id, store::RunState state, const std::string& error = "",
                             const std::string& owner = "") override;

  std::optional<store::RunRecord> claim_next(const std::string& role, const std::string& owner,
                                             std::chrono::milliseconds lease) override;
  bool renew_lease(std::int64_t run_id, const std::string& owner,
                   std::chrono::milliseconds lease) override;
  store::RunRecord add_wall_time(std::int64_t run_id, const WallBreakdown& part,
                                 const std::string& owner = "") override;
  void release(std::int64_t run_id, const std::string& owner) override;
  std::int64_t count_claimable(const std::string& role, const std::string& owner) override;

  void record_metric(std::int64_t run_id, const store::MetricPoint& point, bool reached,
                     std::optional<long long> steps_to_target,
                     const std::string& owner = "") override;
  std::vector<store::MetricPoint> metrics(std::int64_t run_id) override;
  std::vector<store::MetricPoint> metrics_after(std::int64_t run_id,
                                                long long after_env_steps) override;

  store::CheckpointInfo save_checkpoint(std::int64_t run_id, long long env_steps,
                                        double eval_success, std::span<const std::uint8_t> blob,
                                        const std::string& owner = "") override;
  store::CheckpointInfo save_unevaluated(std::int64_t run_id, long long env_steps,
                                         const store::TrainerCounters& counters,
                                         std::span<const std::uint8_t> blob,
                                         const std::string& owner = "") override;
  store::CheckpointInfo record_evaluation(std::int64_t run_id, const store::MetricPoint& point,
                                          std::span<const std::uint8_t> blob, bool reached,
                                          std::optional<long long> steps_to_target,
                                          const std::string& owner = "") override;
  store::Checkpoint load_checkpoint(std::int64_t checkpoint_id) override;
  std::optional<store::CheckpointInfo> latest_checkpoint(std::int64_t run_id) override;
  std::vector<store::CheckpointInfo> checkpoints(std::int64_t run_id) override;
  store::CheckpointInfo checkpoint_info(std::int64_t checkpoint_id) override;

  std::vector<std::int64_t> import_finished(std::span<const store::FinishedRun> runs, bool promote,
                                            const std::string& by = "") override;

  using Store::promote;
  std::vector<store::Promotion> promote(std::span<const std::int64_t> checkpoint_ids,
                                        const std::string& by = "") override;
  std::optional<store::Promotion> promoted(const std::string& role) override;
  std::vector<store::Promotion> promotions() override;

  store::GcReport prune_checkpoints(std::int64_t run_id,
                                    const store::RetentionPolicy& policy) override;
  store::GcReport collect_garbage(const store::RetentionPolicy& policy) override;
  // The store server's consistent copy, written to the local file `destination` (beside
  // it as .partial until whole and verified against the server's checksum).
  store::BackupReport backup(const std::string& destination) override;

  // Calls `on_change` with the whole set of promotions at once and after every change,
  // until `on_change` returns false or `context` is cancelled (from another thread);
  // returns how the stream ended (UNAVAILABLE when the store server went away).
  grpc::Status watch_promotions(
      grpc::ClientContext& context,
      const std::function<bool(std::vector<store::Promotion>)>& on_change);

  const std::string& address() const { return address_; }

 private:
  std::unique_ptr<grpc::ClientContext> context(std::chrono::milliseconds timeout) const;
  // One unary call of the store service: its response, or the service's error as Error.
  template <typename Request, typename Response>
  Response call(grpc::Status (store_v1::StoreService::Stub::*rpc)(grpc::ClientContext*,
                                                                  const Request&, Response*),
                const Request& request, std::string_view what) {
    return call(rpc, request, what, options_.call_timeout);
  }
  template <typename Request, typename Response>
  Response call(grpc::Status (store_v1::StoreService::Stub::*rpc)(grpc::ClientContext*,
                                                                  const Request&, Response*),
                const Request& request, std::string_view what, std::chrono::milliseconds timeout) {
    Response response;
    throw_if_error(((*stub_).*rpc)(context(timeout).get(), request, &response), what, address_);
    return response;
  }
  std::vector<store::MetricPoint> list_metrics(std::int64_t run_id, std::optional<long long> after);
  store::CheckpointInfo save(const store_v1::SaveCheckpointHeader& header,
                             std::span<const std::uint8_t> blob, std::string_view what);

  std::unique_ptr<store_v1::StoreService::Stub> stub_;
  std::string address_;
  RemoteStoreOptions options_;
};

}  // namespace pnp::services
