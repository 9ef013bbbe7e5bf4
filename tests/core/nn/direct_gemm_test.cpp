#include "nn/direct_gemm.h"

#include <cblas.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "nn/cpu_features.h"
#include "support/gemm_reference.h"

namespace pnp::nn {
namespace {

using testing::absolute_gemm;
using testing::reference_gemm;

std::vector<float> random_floats(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// Every path with an unpacked kernel that this CPU can run; the test is skipped, naming
// the CPU's features, when there is none.
std::vector<GemmPath> kernel_paths() {
  std::vector<GemmPath> out;
  for (const GemmPath p : kGemmPaths)
    if (has_direct_kernel(p) && cpu_supports(p, detect_cpu_features())) out.push_back(p);
  return out;
}

#define FOR_EACH_KERNEL_PATH(path)                                                                 \
  if (kernel_paths().empty())                                                                      \
    GTEST_SKIP() << "this CPU has no unpacked kernel (" << describe(detect_cpu_features()) << ")"; \
  for (const GemmPath path : kernel_paths())

struct Shape {
  std::ptrdiff_t m, n, k;
  bool transpose_b, accumulate;
};

DirectGemmOperands operands(const Shape& s, const std::vector<float>& a,
                            const std::vector<float>& b, std::vector<float>& c) {
  DirectGemmOperands op{.m = s.m, .n = s.n, .k = s.k, .a = a.data(), .b = b.data()};
  op.b_row_stride = s.transpose_b ? s.n : 1;
  op.b_col_stride = s.transpose_b ? 1 : s.k;
  op.c = c.data();
  op.accumulate = s.accumulate;
  return op;
}

TEST(DirectGemm, EveryElementIsOneFusedChainThenOneAddition) {
  FOR_EACH_KERNEL_PATH(path) {
    // Full and partial row panels of both kernels (16 and 32 rows), every column-block
    // width of both (6 and 12), k = 0, and k past the depth the AVX2 kernel copies A's
    // panels for (512: deeper products read A in place).
    for (const Shape s :
         {Shape{256, 128, 256, false, true}, Shape{35, 13, 31, false, false},
          Shape{17, 25, 7, true, true}, Shape{64, 12, 0, false, true}, Shape{48, 1, 5, true, false},
          Shape{256, 35, 128, true, true}, Shape{9, 7, 3, false, true},
          Shape{40, 11, 19, true, false}, Shape{8, 5, 2, false, false},
          Shape{40, 7, 600, false, true}, Shape{32, 13, 513, true, false}}) {
      const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 1);
      const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 2);
      auto c = random_floats(static_cast<std::size_t>(s.m * s.n), 3);
      const auto expected = reference_gemm(operands(s, a, b, c), c);
      direct_gemm(path, operands(s, a, b, c));
      EXPECT_EQ(0, std::memcmp(c.data(), expected.data(), c.size() * sizeof(float)))
          << gemm_path_name(path) << " " << s.m << "x" << s.n << "x" << s.k;
    }
  }
}

TEST(DirectGemm, AddsTheBiasToEveryColumnThenAppliesReLU) {
  FOR_EACH_KERNEL_PATH(path) {
    for (const Shape s : {Shape{256, 128, 256, false, false}, Shape{35, 13, 31, false, false}}) {
      const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 7);
      const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 8);
      const auto bias = random_floats(static_cast<std::size_t>(s.m), 9);
      std::vector<float> c(static_cast<std::size_t>(s.m * s.n), 0.0f);
      DirectGemmOperands op = operands(s, a, b, c);
      op.row_bias = bias.data();
      op.relu = true;
      const auto expected = reference_gemm(op, c);
      direct_gemm(path, op);
      EXPECT_EQ(0, std::memcmp(c.data(), expected.data(), c.size() * sizeof(float)))
          << gemm_path_name(path);
      EXPECT_GT(std::count(c.begin(), c.end(), 0.0f), 0);  // ReLU clipped some
    }
    // A NaN stays NaN through the ReLU (as in Eigen's cwiseMax(0)): a diverged network
    // must not look finite.
    const Shape s{32, 16, 4, false, false};
    auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 14);
    // Rows 0, 9 and 20: the low and high register of both kernels' panels.
    for (const std::size_t row : {0u, 9u, 20u}) a[row] = std::numeric_limits<float>::quiet_NaN();
    const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 15);
    const std::vector<float> bias(static_cast<std::size_t>(s.m), 0.0f);
    std::vector<float> c(static_cast<std::size_t>(s.m * s.n), 0.0f);
    DirectGemmOperands op = operands(s, a, b, c);
    op.row_bias = bias.data();
    op.relu = true;
    direct_gemm(path, op);
    for (const std::size_t row : {0u, 9u, 20u})
      EXPECT_TRUE(std::isnan(c[row])) << gemm_path_name(path);
  }
}

TEST(DirectGemm, KeepsOnlyWhereTheReLUOutputIsPositive) {
  FOR_EACH_KERNEL_PATH(path) {
    for (const Shape s : {Shape{256, 37, 256, false, false}, Shape{35, 20, 9, false, false}}) {
      const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 11);
      const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 12);
      auto relu_output = random_floats(static_cast<std::size_t>(s.m * s.n), 13);
      for (float& x : relu_output) x = std::max(x, 0.0f);  // a ReLU's output: half exactly 0
      std::vector<float> c(relu_output.size(), 5.0f);
      DirectGemmOperands op = operands(s, a, b, c);
      op.relu_output = relu_output.data();
      const auto expected = reference_gemm(op, c);
      direct_gemm(path, op);
      EXPECT_EQ(0, std::memcmp(c.data(), expected.data(), c.size() * sizeof(float)))
          << gemm_path_name(path) << " " << s.m << "x" << s.n << "x" << s.k;
      EXPECT_GT(std::count(c.begin(), c.end(), 0.0f), static_cast<long>(c.size() / 4));
    }
  }
}

TEST(DirectGemm, TransposesWholeAndPartialTiles) {
  FOR_EACH_KERNEL_PATH(path) {
    for (const auto& [rows, cols] :
         {std::pair{256, 256}, std::pair{35, 256}, std::pair{256, 35}, std::pair{17, 5},
          std::pair{1, 40}, std::pair{48, 1}, std::pair{8, 8}, std::pair{24, 9}}) {
      const auto src = random_floats(static_cast<std::size_t>(rows * cols), 10);
      std::vector<float> dst(src.size(), -7.0f);
      direct_transpose(path, src.data(), rows, cols, dst.data());
      for (int r = 0; r < rows; ++r) {
        for (int c = 0; c < cols; ++c) {
          ASSERT_EQ(dst[static_cast<std::size_t>(c + r * cols)],
                    src[static_cast<std::size_t>(r + c * rows)])
              << gemm_path_name(path) << " " << rows << "x" << cols << " at (" << r << ", " << c
              << ")";
        }
      }
    }
  }
}

TEST(DirectGemm, APathThisCpuCannotRunIsRefusedNotExecuted) {
  const CpuFeatures cpu = detect_cpu_features();
  std::vector<float> a(32 * 16, 1.0f), b(16 * 16, 1.0f), c(32 * 16, 0.0f);
  const DirectGemmOperands op = operands(Shape{32, 16, 16, false, false}, a, b, c);
  bool refused_any = false;
  for (const GemmPath p : kGemmPaths) {
    if (has_direct_kernel(p) && cpu_supports(p, cpu)) continue;
    refused_any = true;
    EXPECT_THROW(direct_gemm(p, op), pnp::Error) << gemm_path_name(p);
    EXPECT_THROW(direct_transpose(p, a.data(), 32, 16, c.data()), pnp::Error) << gemm_path_name(p);
  }
  EXPECT_TRUE(refused_any);  // openblas has no unpacked kernel on any CPU
}

// The DDPG update's products (3 x 256 layers, 128-sample partitions, critic passes of 256).
const Shape kUpdateShapes[] = {Shape{256, 128, 256, false, true}, Shape{256, 256, 256, false, true},
                               Shape{256, 256, 35, false, true},  Shape{256, 256, 128, true, true},
                               Shape{256, 35, 128, true, true},   Shape{256, 128, 31, false, true}};

// Random operands of one of the update's products, and OpenBLAS's C + A op(B) of them.
struct UpdateProduct {
  std::vector<float> a, b, c, blas;
};

UpdateProduct update_product(const Shape& s) {
  UpdateProduct p{random_floats(static_cast<std::size_t>(s.m * s.k), 4),
                  random_floats(static_cast<std::size_t>(s.k * s.n), 5),
                  random_floats(static_cast<std::size_t>(s.m * s.n), 6),
                  {}};
  p.blas = p.c;
  cblas_sgemm(CblasColMajor, CblasNoTrans, s.transpose_b ? CblasTrans : CblasNoTrans,
              static_cast<blasint>(s.m), static_cast<blasint>(s.n), static_cast<blasint>(s.k), 1.0f,
              p.a.data(), static_cast<blasint>(s.m), p.b.data(),
              static_cast<blasint>(s.transpose_b ? s.n : s.k), 1.0f, p.blas.data(),
              static_cast<blasint>(s.m));
  return p;
}

// Any two summation orders of C + sum_p A(i,p) B(p,j) are each within gamma_{k+1} of the
// exact value, times sum_p |A(i,p) B(p,j)| + |C(i,j)| (the standard forward error bound
// of a dot product, Higham, Accuracy and Stability, 3.1), so they differ by at most twice
// that: a bound that holds whatever order an OpenBLAS kernel picks.
TEST(DirectGemm, UpdateShapesAgreeWithOpenBlasWithinTheRoundingBound) {
  FOR_EACH_KERNEL_PATH(path) {
    for (const Shape s : kUpdateShapes) {
      UpdateProduct p = update_product(s);
      const DirectGemmOperands op = operands(s, p.a, p.b, p.c);
      const auto magnitude = absolute_gemm(op, p.c);  // sum |A||B| + |C|, in double
      direct_gemm(path, op);
      const double u = std::ldexp(1.0, -24), n = static_cast<double>(s.k + 1);
      const double gamma = n * u / (1.0 - n * u);
      for (std::size_t e = 0; e < p.c.size(); ++e) {
        ASSERT_LE(std::abs(static_cast<double>(p.c[e]) - static_cast<double>(p.blas[e])),
                  2.0 * gamma * magnitude[e])
            << gemm_path_name(path) << " " << s.m << "x" << s.n << "x" << s.k << " element " << e;
      }
    }
  }
}

// Where OpenBLAS runs its SkylakeX kernel (the one whose order the kernels follow),
// moving the update's products to them changes no bit, so no learning result either.
TEST(DirectGemm, UpdateShapesMatchOpenBlasSkylakeXBitForBit) {
  const std::string core = openblas_get_corename();
  if (core != "SkylakeX")
    GTEST_SKIP() << "OpenBLAS runs its " << core << " kernel here, which sums in another order "
                 << "(bit-identity holds only with SkylakeX; set OPENBLAS_CORETYPE=SkylakeX on "
                 << "an AVX-512 CPU to check it)";
  FOR_EACH_KERNEL_PATH(path) {
    for (const Shape s : kUpdateShapes) {
      UpdateProduct p = update_product(s);
      direct_gemm(path, operands(s, p.a, p.b, p.c));
      EXPECT_EQ(0, std::memcmp(p.c.data(), p.blas.data(), p.c.size() * sizeof(float)))
          << gemm_path_name(path) << " " << s.m << "x" << s.n << "x" << s.k;
    }
  }
}

}  // namespace
}  // namespace pnp::nn
