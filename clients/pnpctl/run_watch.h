#pragma once
// Follows a training run through WatchTrainingRun until it ends (through another replica
// of the training service if the one watched goes away), drawing a live progress
// bar on a terminal (one line per evaluation otherwise, e.g. in CI logs).

#include <cstdio>
#include <string>

#include "clients/pnpctl/endpoints.h"
#include "pnp/train/v1/train_service.pb.h"

namespace pnp::pnpctl {

struct WatchOptions {
  bool quiet = false;  // nothing on the progress stream
  std::FILE* progress = stderr;
};

// The run as it ended. Throws pnp::Error if the stream fails.
train::v1::TrainingRun watch_run(const Endpoints& endpoints, const std::string& address,
                                 std::int64_t run_id, const WatchOptions& options);

}  // namespace pnp::pnpctl
