#include "nn/gemm_path.h"

#include <gtest/gtest.h>

#include "support/refusal.h"

namespace pnp::nn {
namespace {

using testing::refusal;

constexpr CpuFeatures kAvx512Cpu{.avx512f = true, .avx2 = true, .fma = true};
constexpr CpuFeatures kAvx2Cpu{.avx512f = false, .avx2 = true, .fma = true};
constexpr CpuFeatures kBaselineCpu{};

TEST(GemmPath, AutoPicksTheFastestMeasuredPathTheCpuHas) {
  EXPECT_EQ(resolve_gemm_path("", kAvx512Cpu), GemmPath::kAvx512);
  EXPECT_EQ(resolve_gemm_path("auto", kAvx512Cpu), GemmPath::kAvx512);
  // OpenBLAS's Zen kernel beats the AVX2 kernel (docs/BENCHMARKS.md).
  EXPECT_EQ(resolve_gemm_path("auto", kAvx2Cpu), GemmPath::kOpenBlas);
  EXPECT_EQ(resolve_gemm_path("auto", kBaselineCpu), GemmPath::kOpenBlas);
  // AVX2 without FMA (some virtual machines report that) cannot run the kernel.
  EXPECT_EQ(resolve_gemm_path("auto", CpuFeatures{.avx2 = true}), GemmPath::kOpenBlas);
}

TEST(GemmPath, AForcedPathIsTakenWhereTheCpuHasIt) {
  EXPECT_EQ(resolve_gemm_path("avx2", kAvx512Cpu), GemmPath::kAvx2);
  EXPECT_EQ(resolve_gemm_path("openblas", kAvx512Cpu), GemmPath::kOpenBlas);
  EXPECT_EQ(resolve_gemm_path("openblas", kBaselineCpu), GemmPath::kOpenBlas);
}

TEST(GemmPath, APathTheCpuLacksIsRefusedNamingTheVariableAndTheFeatures) {
  EXPECT_EQ(refusal([] { resolve_gemm_path("avx512", kAvx2Cpu); }),
            "PNP_GEMM: expected auto, avx2, openblas (this CPU has avx2 fma), got \"avx512\": "
            "a path this CPU cannot run");
  EXPECT_EQ(refusal([] { resolve_gemm_path("avx2", kBaselineCpu); }),
            "PNP_GEMM: expected auto, openblas (this CPU has none of avx512f, avx2, fma), got "
            "\"avx2\": a path this CPU cannot run");
}

TEST(GemmPath, AnUnknownValueIsRefusedNamingTheVariable) {
  EXPECT_EQ(refusal([] { resolve_gemm_path("AVX2", kAvx512Cpu); }),
            "PNP_GEMM: expected auto, avx512, avx2, openblas (this CPU has avx512f avx2 fma), got "
            "\"AVX2\"");
  EXPECT_EQ(refusal([] { resolve_gemm_path("mkl", kAvx2Cpu); }),
            "PNP_GEMM: expected auto, avx2, openblas (this CPU has avx2 fma), got \"mkl\"");
}

TEST(GemmPath, NamesRoundTrip) {
  for (const GemmPath p : kGemmPaths) EXPECT_EQ(parse_gemm_path(gemm_path_name(p)), p);
  EXPECT_FALSE(parse_gemm_path("auto"));
}

TEST(GemmPath, ThisProcessRunsAPathItsCpuHas) {
  EXPECT_TRUE(cpu_supports(active_gemm_path(), detect_cpu_features()));
}

}  // namespace
}  // namespace pnp::nn
