#include "nn/direct_gemm.h"

#include <string>

#include "common/error.h"
#include "nn/cpu_features.h"
#include "nn/direct_gemm_kernels.h"

namespace pnp::nn {
namespace {

// Running a kernel on a CPU without its instruction set would end the process with
// SIGILL: refused as a broken invariant instead (callers pick paths the CPU supports).
void require_kernel(GemmPath path, const char* caller) {
  static const CpuFeatures cpu = detect_cpu_features();
  if (!has_direct_kernel(path) || !cpu_supports(path, cpu)) {
    throw_internal(std::string(caller) + ": no unpacked kernel for path " +
                   std::string(gemm_path_name(path)) + " on this CPU (" + describe(cpu) + ")");
  }
}

}  // namespace

bool has_direct_kernel(GemmPath path) {
  return path == GemmPath::kAvx512 || path == GemmPath::kAvx2;
}

void direct_gemm(GemmPath path, const DirectGemmOperands& op) {
  require_kernel(path, "direct_gemm");
  if (op.m < 0 || op.n < 0 || op.k < 0) throw_internal("direct_gemm: negative dimension");
  if (op.accumulate && op.row_bias) throw_internal("direct_gemm: accumulate or bias, not both");
  if (path == GemmPath::kAvx512)
    avx512::gemm(op);
  else
    avx2::gemm(op);
}

void direct_transpose(GemmPath path, const float* src, std::ptrdiff_t rows, std::ptrdiff_t cols,
                      float* dst) {
  require_kernel(path, "direct_transpose");
  if (rows < 0 || cols < 0) throw_internal("direct_transpose: negative dimension");
  if (path == GemmPath::kAvx512)
    avx512::transpose(src, rows, cols, dst);
  else
    avx2::transpose(src, rows, cols, dst);
}

}  // namespace pnp::nn
