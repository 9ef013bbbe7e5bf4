#include "clients/pnpctl/run_watch.h"

#include <unistd.h>

#include <algorithm>

#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/table.h"
#include "pnp/train/v1/train_service.grpc.pb.h"

namespace pnp::pnpctl {
namespace {

std::string steps_text(long long steps) {
  return fixed(static_cast<double>(steps) / 1000, 1) + "k";
}

}  // namespace

std::string progress_line(const train::v1::TrainingRun& run, const train::v1::MetricPoint* metric,
                          int width) {
  const double fraction =
      run.max_steps() > 0
          ? std::clamp(static_cast<double>(run.env_steps()) / static_cast<double>(run.max_steps()),
                       0.0, 1.0)
          : 0.0;
  const int filled = static_cast<int>(fraction * width);
  std::string line = short_name(run.role()) + "  run " + std::to_string(run.run_id()) + "  [" +
                     std::string(static_cast<std::size_t>(filled), '#') +
                     std::string(static_cast<std::size_t>(width - filled), '-') + "]  " +
                     steps_text(run.env_steps()) + "/" + steps_text(run.max_steps()) + " steps";
  line += "  success " + fixed(metric ? metric->task_success() : run.last_success(), 2);
  if (metric && metric->sampled_success() > 0)
    line += "  sampled " + fixed(metric->sampled_success(), 2);
  if (run.has_eta()) line += "  eta<=" + duration_text(static_cast<double>(run.eta().seconds()));
  line += "  " + short_name(run.state());
  return line;
}

train::v1::TrainingRun watch_run(const std::string& address, std::int64_t run_id,
                                 const WatchOptions& options) {
  auto stub = train::v1::TrainingService::NewStub(channel(address));
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
