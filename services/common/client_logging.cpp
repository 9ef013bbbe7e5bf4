#include "services/common/client_logging.h"

#include <grpc/support/log.h>

#include <cstdlib>

namespace pnp::services {

void quiet_grpc_logs_unless_asked() {
  if (std::getenv("GRPC_VERBOSITY") != nullptr) return;
  gpr_set_log_function([](gpr_log_func_args*) {});
}

}  // namespace pnp::services
