#include "nn/gemm_path.h"

#include <cstdlib>
#include <string>

#include "common/error.h"

namespace pnp::nn {

std::string_view gemm_path_name(GemmPath path) {
  switch (path) {
    case GemmPath::kAvx512:
      return "avx512";
    case GemmPath::kAvx2:
      return "avx2";
    case GemmPath::kOpenBlas:
      return "openblas";
  }
  throw_internal("gemm_path_name: unknown path");
}

std::optional<GemmPath> parse_gemm_path(std::string_view name) {
  for (const GemmPath p : kGemmPaths)
    if (gemm_path_name(p) == name) return p;
  return std::nullopt;
}

bool cpu_supports(GemmPath path, const CpuFeatures& cpu) {
  switch (path) {
    case GemmPath::kAvx512:
      return cpu.avx512f;
    case GemmPath::kAvx2:
      return cpu.avx2 && cpu.fma;
    case GemmPath::kOpenBlas:
      return true;
  }
  return false;
}

GemmPath resolve_gemm_path(std::string_view requested, const CpuFeatures& cpu) {
  if (requested.empty() || requested == "auto") {
    for (const GemmPath p : kAutoPreference)
      if (cpu_supports(p, cpu)) return p;
  }
  const std::optional<GemmPath> path = parse_gemm_path(requested);
  if (!path || !cpu_supports(*path, cpu)) {
    std::string supported;
    for (const GemmPath p : kGemmPaths)
      if (cpu_supports(p, cpu)) supported.append(", ").append(gemm_path_name(p));
    throw Error(ErrorCode::kInvalidArgument, "PNP_GEMM: expected auto" + supported +
                                                 " (this CPU has " + describe(cpu) + "), got \"" +
                                                 std::string(requested) + "\"" +
                                                 (path ? ": a path this CPU cannot run" : ""));
  }
  return *path;
}

GemmPath active_gemm_path() {
  // A function-local static: resolved once, thread-safe, immutable afterwards. A throwing
  // initialisation leaves it unset, so a bad value is refused at every call.
  static const GemmPath path = [] {
    const char* requested = std::getenv("PNP_GEMM");
    return resolve_gemm_path(requested ? requested : "", detect_cpu_features());
  }();
  return path;
}

}  // namespace pnp::nn
