#include "clients/pnpctl/run_watch.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/run_display.h"
#include "pnp/train/v1/train_service.grpc.pb.h"

namespace pnp::pnpctl {
namespace {

// A training replica that goes away (killed, drained, rescheduled) ends the watch with
// UNAVAILABLE while the run itself lives on in the store, taken over by another replica.
// The watch is opened again, through the same target, as long as some replica answers
// within this many consecutive attempts (about 15 s of backoff).
constexpr int kReopenAttempts = 10;
constexpr auto kFirstBackoff = std::chrono::milliseconds(200);
constexpr auto kMaxBackoff = std::chrono::seconds(2);

}  // namespace

train::v1::TrainingRun watch_run(const Endpoints& endpoints, const std::string& address,
                                 std::int64_t run_id, const WatchOptions& options) {
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  train::v1::WatchTrainingRunRequest request;
  request.set_run_id(run_id);
  const bool terminal = ::isatty(::fileno(options.progress)) != 0;
  train::v1::TrainingRun last;
  int failed_attempts = 0;
  auto backoff = std::chrono::duration_cast<std::chrono::milliseconds>(kFirstBackoff);
  while (true) {
    grpc::ClientContext context;
    auto reader = stub->WatchTrainingRun(&context, request);
    for (train::v1::WatchTrainingRunResponse message; reader->Read(&message);) {
      failed_attempts = 0;
      backoff = kFirstBackoff;
      last = message.run();
      if (options.quiet) continue;
      const std::string line =
          progress_line(message.run(), message.has_metric() ? &message.metric() : nullptr, 24);
      if (terminal) {
        std::fprintf(options.progress, "\r\033[K%s", line.c_str());
      } else if (message.has_metric()) {
        std::fprintf(options.progress, "%s\n", line.c_str());
      }
      std::fflush(options.progress);
    }
    const grpc::Status status = reader->Finish();
    if (status.error_code() != grpc::StatusCode::UNAVAILABLE ||
        ++failed_attempts > kReopenAttempts) {
      if (terminal && !options.quiet) std::fprintf(options.progress, "\n");
      check(status, "WatchTrainingRun", address);
      return last;
    }
    if (!options.quiet) {
      std::fprintf(options.progress, "%swatching run %lld again: %s\n", terminal ? "\r\033[K" : "",
                   static_cast<long long>(run_id), status.error_message().c_str());
    }
    std::this_thread::sleep_for(backoff);
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, kMaxBackoff);
  }
}

}  // namespace pnp::pnpctl
