#include "clients/pnpctl/run_watch.h"

#include <unistd.h>

#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/run_display.h"
#include "pnp/train/v1/train_service.grpc.pb.h"

namespace pnp::pnpctl {

train::v1::TrainingRun watch_run(const Endpoints& endpoints, const std::string& address,
                                 std::int64_t run_id, const WatchOptions& options) {
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  grpc::ClientContext context;
  train::v1::WatchTrainingRunRequest request;
  request.set_run_id(run_id);
  auto reader = stub->WatchTrainingRun(&context, request);
  const bool terminal = ::isatty(::fileno(options.progress)) != 0;
  train::v1::TrainingRun last;
  for (train::v1::WatchTrainingRunResponse message; reader->Read(&message);) {
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
  if (terminal && !options.quiet) std::fprintf(options.progress, "\n");
  check(reader->Finish(), "WatchTrainingRun", address);
  return last;
}

}  // namespace pnp::pnpctl
