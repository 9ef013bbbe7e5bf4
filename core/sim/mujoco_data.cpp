#include "sim/mujoco_data.h"

#include <cstdio>
#include <mutex>

#include "common/error.h"

namespace pnp::sim {
namespace {

void warning_to_stderr(const char* message) {
  std::fprintf(stderr, "mujoco: %s\n", message);
}

}  // namespace

DataPtr make_data(const mjModel* m) {
  DataPtr data(mj_makeData(m));
  if (!data) throw_internal("mj_makeData failed: out of memory");
  return data;
}

void route_mujoco_messages() {
  // MuJoCo's handler slot is process-wide by design; it is set once, to a stateless
  // function, before any model is compiled.
  static std::once_flag once;
  std::call_once(once, [] { mju_user_warning = warning_to_stderr; });
}

}  // namespace pnp::sim
