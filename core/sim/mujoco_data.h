#pragma once
// RAII ownership of MuJoCo's C structures, and the one-time redirection of MuJoCo's
// messages (by default it prints warnings to stdout and appends them to MUJOCO_LOG.TXT
// in the working directory, which would corrupt JSON output and litter run folders).

#include <mujoco/mujoco.h>

#include <memory>

namespace pnp::sim {

struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

DataPtr make_data(const mjModel* m);

// Routes MuJoCo warnings to stderr. Idempotent and thread-safe. Environments do not rely
// on the text: they detect instability from mjData::warning counters.
void route_mujoco_messages();

}  // namespace pnp::sim
