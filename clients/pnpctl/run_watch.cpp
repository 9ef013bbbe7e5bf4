#include "clients/pnpctl/run_watch.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>

#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/run_display.h"
#include "pnp/train/v1/train_service.grpc.pb.h"

namespace pnp::pnpctl {
namespace {

// A training replica that goes away (killed, drained, rescheduled) ends the watch with
// UNAVAILABLE while the run itself lives on in the store, taken over by another replica
// (or by the same one restarted). The watch is opened again through the same target once
// the channel connects, for up to this long without an answer: enough for a Pod to be
// replaced and its lease to expire.
constexpr auto kReopenBudget = std::chrono::minutes(5);
constexpr auto kFirstBackoff = std::chrono::milliseconds(200);
constexpr auto kMaxBackoff = std::chrono::seconds(5);

// One line per evaluation, or the live bar redrawn on a terminal.
void show(const train::v1::WatchTrainingRunResponse& message, const WatchOptions& options,
          bool terminal) {
  if (options.quiet) return;
  const std::string line =
      progress_line(message.run(), message.has_metric() ? &message.metric() : nullptr, 24);
  if (terminal) {
    std::fprintf(options.progress, "\r\033[K%s", line.c_str());
  } else if (message.has_metric()) {
    std::fprintf(options.progress, "%s\n", line.c_str());
  }
  std::fflush(options.progress);
}

}  // namespace

train::v1::TrainingRun watch_run(const Endpoints& endpoints, const std::string& address,
                                 std::int64_t run_id, const WatchOptions& options) {
  const auto channel = endpoints.channel(address);
  auto stub = train::v1::TrainingService::NewStub(channel);
  train::v1::WatchTrainingRunRequest request;
  request.set_run_id(run_id);
  const bool terminal = ::isatty(::fileno(options.progress)) != 0;
  train::v1::TrainingRun last;
  auto answered_at = std::chrono::steady_clock::now();
  auto backoff = std::chrono::duration_cast<std::chrono::milliseconds>(kFirstBackoff);
  bool announced = false;  // this outage has been said
  while (true) {
    grpc::ClientContext context;
    auto reader = stub->WatchTrainingRun(&context, request);
    for (train::v1::WatchTrainingRunResponse message; reader->Read(&message);) {
      answered_at = std::chrono::steady_clock::now();
      backoff = kFirstBackoff;
      announced = false;
      last = message.run();
      if (!message.heartbeat()) show(message, options, terminal);
    }
    const grpc::Status status = reader->Finish();
    if (status.error_code() != grpc::StatusCode::UNAVAILABLE ||
        std::chrono::steady_clock::now() - answered_at > kReopenBudget) {
      if (terminal && !options.quiet) std::fprintf(options.progress, "\n");
      check(status, "WatchTrainingRun", address);
      return last;
    }
    if (!options.quiet && !announced) {
      std::fprintf(options.progress, "%swatching run %lld again: %s\n", terminal ? "\r\033[K" : "",
                   static_cast<long long>(run_id), status.error_message().c_str());
      announced = true;
    }
    // The backoff, cut short once a replica accepts a connection.
    channel->WaitForConnected(std::chrono::system_clock::now() + backoff);
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, kMaxBackoff);
  }
}

}  // namespace pnp::pnpctl
