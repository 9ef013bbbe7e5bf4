#pragma once
// Which code computes the networks' batched products. One binary carries every path and
// picks one at run time from the CPU's features, so a portable build (PNP_NATIVE=OFF, the
// Docker image) gets the kernels as a -march=native one does:
//   avx512    the unpacked kernel on 512-bit registers (nn/direct_gemm_avx512.cpp)
//   avx2      the same kernel on 256-bit registers with FMA (nn/direct_gemm_avx2.cpp)
//   openblas  OpenBLAS for every product (any x86-64)
// Both kernels compute every element as one fused multiply-add chain over k from zero,
// then one addition: the two give the same bits as each other and as the scalar
// reference in the tests. OpenBLAS sums in an order of its own that depends on the kernel
// it picks for the CPU (or OPENBLAS_CORETYPE), so runs on the openblas path, or on
// different machines' OpenBLAS, give different, equally valid curves.
//
// PNP_GEMM=auto|avx512|avx2|openblas forces a path (auto, or unset: kAutoPreference, the
// fastest measured); an unknown value or a path the CPU lacks is refused naming the
// variable.

#include <optional>
#include <string_view>

#include "nn/cpu_features.h"

namespace pnp::nn {

enum class GemmPath { kAvx512, kAvx2, kOpenBlas };

inline constexpr GemmPath kGemmPaths[] = {GemmPath::kAvx512, GemmPath::kAvx2, GemmPath::kOpenBlas};
// What auto takes: the first the CPU supports. avx2 is not in it: on an AMD EPYC (Zen 3)
// the update ran 101-132 updates/s on it against 137-146 on OpenBLAS's Zen kernel
// (docs/BENCHMARKS.md). It is a path to ask for: it reproduces the avx512 path's bits on
// a CPU without AVX-512.
inline constexpr GemmPath kAutoPreference[] = {GemmPath::kAvx512, GemmPath::kOpenBlas};

std::string_view gemm_path_name(GemmPath path);
std::optional<GemmPath> parse_gemm_path(std::string_view name);

bool cpu_supports(GemmPath path, const CpuFeatures& cpu);

// The path for a PNP_GEMM value ("" or "auto": the first of kAutoPreference `cpu` has);
// throws InvalidArgument naming PNP_GEMM, the accepted values and the CPU's features.
GemmPath resolve_gemm_path(std::string_view requested, const CpuFeatures& cpu);

// This process's path: PNP_GEMM resolved against this CPU once, at the first call, and
// fixed from then on. Throws as resolve_gemm_path (again at every call) for a bad value;
// programs call it at start to refuse one before any work.
GemmPath active_gemm_path();

}  // namespace pnp::nn
