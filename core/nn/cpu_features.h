#pragma once
// The instruction sets the GEMM kernels can use, as this CPU and its OS report them (the
// OS must save the wide registers too, which the compiler's CPU check includes).

#include <string>

namespace pnp::nn {

struct CpuFeatures {
  bool avx512f = false;
  bool avx2 = false;
  bool fma = false;
};

CpuFeatures detect_cpu_features();

// "avx512f avx2 fma" style, or "none of avx512f, avx2, fma": for messages and reports.
std::string describe(const CpuFeatures& features);

}  // namespace pnp::nn
