#include "nn/blas_threads.h"

#include <mutex>

extern "C" void openblas_set_num_threads(int num_threads);

namespace pnp::nn {

void pin_blas_to_one_thread() {
  static std::once_flag once;
  std::call_once(once, [] { openblas_set_num_threads(1); });
}

}  // namespace pnp::nn
