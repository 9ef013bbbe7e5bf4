#include "nn/direct_gemm.h"

#include <cblas.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "common/rng.h"
#include "nn/mlp.h"

namespace pnp::nn {
namespace {

std::vector<float> random_floats(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// The arithmetic the kernel promises: one fused multiply-add chain over k from zero per
// element, then one addition to C.
std::vector<float> reference(const DirectGemmOperands& op, std::vector<float> c) {
  for (std::ptrdiff_t j = 0; j < op.n; ++j) {
    for (std::ptrdiff_t i = 0; i < op.m; ++i) {
      float acc = 0.0f;
      for (std::ptrdiff_t p = 0; p < op.k; ++p)
        acc = std::fma(op.a[i + p * op.m], op.b[p * op.b_row_stride + j * op.b_col_stride], acc);
      float& out = c[static_cast<std::size_t>(i + j * op.m)];
      out = op.accumulate ? out + acc : op.row_bias ? op.row_bias[i] + acc : acc;
      if (op.relu) out = std::max(out, 0.0f);
      if (op.relu_output && !(op.relu_output[i + j * op.m] > 0.0f)) out = 0.0f;
    }
  }
  return c;
}

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
  if (!direct_gemm_available()) GTEST_SKIP() << "no AVX-512 kernel in this build";
  // Full and partial row panels, every column-block width, k = 0.
  for (const Shape s : {Shape{256, 128, 256, false, true}, Shape{35, 13, 31, false, false},
                        Shape{17, 25, 7, true, true}, Shape{64, 12, 0, false, true},
                        Shape{48, 1, 5, true, false}, Shape{256, 35, 128, true, true}}) {
    const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 1);
    const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 2);
    auto c = random_floats(static_cast<std::size_t>(s.m * s.n), 3);
    const auto expected = reference(operands(s, a, b, c), c);
    direct_gemm(operands(s, a, b, c));
    EXPECT_EQ(0, std::memcmp(c.data(), expected.data(), c.size() * sizeof(float)))
        << s.m << "x" << s.n << "x" << s.k;
  }
}

TEST(DirectGemm, AddsTheBiasToEveryColumnThenAppliesReLU) {
  if (!direct_gemm_available()) GTEST_SKIP() << "no AVX-512 kernel in this build";
  for (const Shape s : {Shape{256, 128, 256, false, false}, Shape{35, 13, 31, false, false}}) {
    const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 7);
    const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 8);
    const auto bias = random_floats(static_cast<std::size_t>(s.m), 9);
    std::vector<float> c(static_cast<std::size_t>(s.m * s.n), 0.0f);
    DirectGemmOperands op = operands(s, a, b, c);
    op.row_bias = bias.data();
    op.relu = true;
    const auto expected = reference(op, c);
    direct_gemm(op);
    EXPECT_EQ(0, std::memcmp(c.data(), expected.data(), c.size() * sizeof(float)));
    EXPECT_GT(std::count(c.begin(), c.end(), 0.0f), 0);  // ReLU clipped some
  }
  // A NaN stays NaN through the ReLU (as in Eigen's cwiseMax(0)): a diverged network must
  // not look finite.
  const Shape s{32, 16, 4, false, false};
  auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 14);
  a[0] = std::numeric_limits<float>::quiet_NaN();
  const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 15);
  const std::vector<float> bias(static_cast<std::size_t>(s.m), 0.0f);
  std::vector<float> c(static_cast<std::size_t>(s.m * s.n), 0.0f);
  DirectGemmOperands op = operands(s, a, b, c);
  op.row_bias = bias.data();
  op.relu = true;
  direct_gemm(op);
  EXPECT_TRUE(std::isnan(c[0]));
}

TEST(DirectGemm, KeepsOnlyWhereTheReLUOutputIsPositive) {
  if (!direct_gemm_available()) GTEST_SKIP() << "no AVX-512 kernel in this build";
  const Shape s{256, 37, 256, false, false};
  const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 11);
  const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 12);
  auto relu_output = random_floats(static_cast<std::size_t>(s.m * s.n), 13);
  for (float& x : relu_output) x = std::max(x, 0.0f);  // a ReLU's output: half exactly 0
  std::vector<float> c(relu_output.size(), 5.0f);
  DirectGemmOperands op = operands(s, a, b, c);
  op.relu_output = relu_output.data();
  const auto expected = reference(op, c);
  direct_gemm(op);
  EXPECT_EQ(0, std::memcmp(c.data(), expected.data(), c.size() * sizeof(float)));
  EXPECT_GT(std::count(c.begin(), c.end(), 0.0f), static_cast<long>(c.size() / 4));
}

TEST(DirectGemm, TransposesWholeAndPartialTiles) {
  if (!direct_gemm_available()) GTEST_SKIP() << "no AVX-512 kernel in this build";
  for (const auto& [rows, cols] : {std::pair{256, 256}, std::pair{35, 256}, std::pair{17, 5},
                                   std::pair{1, 40}, std::pair{48, 1}}) {
    const auto src = random_floats(static_cast<std::size_t>(rows * cols), 10);
    std::vector<float> dst(src.size(), -7.0f);
    direct_transpose(src.data(), rows, cols, dst.data());
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        ASSERT_EQ(dst[static_cast<std::size_t>(c + r * cols)],
                  src[static_cast<std::size_t>(r + c * rows)])
            << rows << "x" << cols << " at (" << r << ", " << c << ")";
      }
    }
  }
}

// The DDPG update's products (3 x 256 layers, 128-sample partitions, critic passes of 256)
// give the same bits as OpenBLAS, so moving them to the kernel changed no learning result.
TEST(DirectGemm, UpdateShapesMatchOpenBlasBitForBit) {
  if (!direct_gemm_available()) GTEST_SKIP() << "no AVX-512 kernel in this build";
  for (const Shape s : {Shape{256, 128, 256, false, true}, Shape{256, 256, 256, false, true},
                        Shape{256, 256, 35, false, true}, Shape{256, 256, 128, true, true},
                        Shape{256, 35, 128, true, true}, Shape{256, 128, 31, false, true}}) {
    const auto a = random_floats(static_cast<std::size_t>(s.m * s.k), 4);
    const auto b = random_floats(static_cast<std::size_t>(s.k * s.n), 5);
    auto ours = random_floats(static_cast<std::size_t>(s.m * s.n), 6);
    auto blas = ours;
    direct_gemm(operands(s, a, b, ours));
    cblas_sgemm(CblasColMajor, CblasNoTrans, s.transpose_b ? CblasTrans : CblasNoTrans,
                static_cast<blasint>(s.m), static_cast<blasint>(s.n), static_cast<blasint>(s.k),
                1.0f, a.data(), static_cast<blasint>(s.m), b.data(),
                static_cast<blasint>(s.transpose_b ? s.n : s.k), 1.0f, blas.data(),
                static_cast<blasint>(s.m));
    EXPECT_EQ(0, std::memcmp(ours.data(), blas.data(), ours.size() * sizeof(float)))
        << s.m << "x" << s.n << "x" << s.k;
  }
}

// The critic's pass in the DDPG update (35 inputs, 3 x 256 ReLU, batch 256, parameter
// gradients from the first 128 samples) through Mlp, with the bias, ReLU and ReLU
// derivative fused into the kernel, against the same pass done step by step with OpenBLAS.
TEST(DirectGemm, AWholeNetworkMatchesTheUnfusedOpenBlasPassBitForBit) {
  Rng rng(21);
  Mlp net({35, {256, 256, 256}, 1, Activation::kReLU, Activation::kNone});
  net.initialise(rng);
  const Eigen::Index n = 256, wc = 128;
  Matrix x(35, n), dy(1, n);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = static_cast<float>(rng.normal());
  for (Eigen::Index i = 0; i < dy.size(); ++i) dy.data()[i] = static_cast<float>(rng.normal());

  MlpWorkspace ws;
  const Matrix y = net.forward(x, ws);
  AlignedFloats grads(net.params().size(), 0.0f);
  Matrix dx;
  net.backward_into(ws, dy, grads, &dx, wc);

  const int layers = net.layers();
  const auto offset = [&](const float* p) { return p - net.params().data(); };
  std::vector<Matrix> post(static_cast<std::size_t>(layers));
  const Matrix* in = &x;
  for (int l = 0; l < layers; ++l) {
    const auto w = net.weight(l);
    Matrix& z = post[static_cast<std::size_t>(l)];
    z = net.bias(l).replicate(1, n);
    cblas_sgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, static_cast<blasint>(w.rows()),
                static_cast<blasint>(n), static_cast<blasint>(w.cols()), 1.0f, w.data(),
                static_cast<blasint>(w.rows()), in->data(), static_cast<blasint>(w.cols()), 1.0f,
                z.data(), static_cast<blasint>(w.rows()));
    if (l + 1 < layers) z = z.cwiseMax(0.0f);
    in = &z;
  }
  AlignedFloats expected_grads(grads.size(), 0.0f);
  Matrix upstream = dy, grad_z, expected_dx;
  for (int l = layers; l-- > 0;) {
    const auto& out = post[static_cast<std::size_t>(l)];
    grad_z =
        l + 1 < layers ? Matrix((out.array() > 0.0f).select(upstream.array(), 0.0f)) : upstream;
    const Matrix& input = l == 0 ? x : post[static_cast<std::size_t>(l - 1)];
    const auto w = net.weight(l);
    cblas_sgemm(CblasColMajor, CblasNoTrans, CblasTrans, static_cast<blasint>(w.rows()),
                static_cast<blasint>(w.cols()), static_cast<blasint>(wc), 1.0f, grad_z.data(),
                static_cast<blasint>(w.rows()), input.data(), static_cast<blasint>(w.cols()), 1.0f,
                expected_grads.data() + offset(w.data()), static_cast<blasint>(w.rows()));
    VectorMap(expected_grads.data() + offset(net.bias(l).data()), w.rows()) +=
        grad_z.leftCols(wc).rowwise().sum();
    Matrix& next = l == 0 ? expected_dx : upstream;
    Matrix product(w.cols(), n);
    cblas_sgemm(CblasColMajor, CblasTrans, CblasNoTrans, static_cast<blasint>(w.cols()),
                static_cast<blasint>(n), static_cast<blasint>(w.rows()), 1.0f, w.data(),
                static_cast<blasint>(w.rows()), grad_z.data(), static_cast<blasint>(w.rows()), 0.0f,
                product.data(), static_cast<blasint>(w.cols()));
    next = product;
  }
  ASSERT_EQ(y.size(), post.back().size());
  EXPECT_EQ(0, std::memcmp(y.data(), post.back().data(),
                           sizeof(float) * static_cast<std::size_t>(y.size())));
  EXPECT_EQ(0, std::memcmp(grads.data(), expected_grads.data(), sizeof(float) * grads.size()));
  ASSERT_EQ(dx.size(), expected_dx.size());
  EXPECT_EQ(0, std::memcmp(dx.data(), expected_dx.data(),
                           sizeof(float) * static_cast<std::size_t>(dx.size())));
}

}  // namespace
}  // namespace pnp::nn
