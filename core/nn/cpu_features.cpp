#include "nn/cpu_features.h"

namespace pnp::nn {

CpuFeatures detect_cpu_features() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return {.avx512f = __builtin_cpu_supports("avx512f") != 0,
          .avx2 = __builtin_cpu_supports("avx2") != 0,
          .fma = __builtin_cpu_supports("fma") != 0};
#else
  return {};
#endif
}

std::string describe(const CpuFeatures& features) {
  std::string out;
  const auto add = [&out](bool present, const char* name) {
    if (!present) return;
    if (!out.empty()) out += ' ';
    out += name;
  };
  add(features.avx512f, "avx512f");
  add(features.avx2, "avx2");
  add(features.fma, "fma");
  return out.empty() ? "none of avx512f, avx2, fma" : out;
}

}  // namespace pnp::nn
