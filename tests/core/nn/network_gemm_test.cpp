// A whole network through Mlp on this process's GEMM path (PNP_GEMM; ctest runs this
// suite on every path the CPU has), against the same pass done step by step, unfused:
// each product the path gives to an unpacked kernel computed by the scalar reference, each
// other one by OpenBLAS, as nn/gemm.cpp splits them.

#include <cblas.h>
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "common/rng.h"
#include "nn/gemm.h"
#include "nn/gemm_path.h"
#include "nn/mlp.h"
#include "support/gemm_reference.h"

namespace pnp::nn {
namespace {

// C (m x n) (+)= A (m x k, as stored) op(B), where B is b_rows x b_cols column-major.
void product(const float* a, Eigen::Index m, Eigen::Index k, bool transpose_b, const float* b,
             Eigen::Index b_rows, Eigen::Index n, float* c) {
  if (has_direct_kernel(active_gemm_path()) && m >= kDirectMinRows && n >= kBlasMinColumns) {
    DirectGemmOperands op{.m = m, .n = n, .k = k, .a = a, .b = b, .c = c, .accumulate = true};
    op.b_row_stride = transpose_b ? b_rows : 1;
    op.b_col_stride = transpose_b ? 1 : b_rows;
    const std::vector<float> before(c, c + m * n);
    const std::vector<float> after = testing::reference_gemm(op, before);
    std::memcpy(c, after.data(), sizeof(float) * after.size());
    return;
  }
  cblas_sgemm(CblasColMajor, CblasNoTrans, transpose_b ? CblasTrans : CblasNoTrans,
              static_cast<blasint>(m), static_cast<blasint>(n), static_cast<blasint>(k), 1.0f, a,
              static_cast<blasint>(m), b, static_cast<blasint>(b_rows), 1.0f, c,
              static_cast<blasint>(m));
}

// dst = W^T dz: a kernel's product over W transposed into scratch, or OpenBLAS's.
Matrix input_gradient(const Eigen::Ref<const Matrix>& w, const Matrix& dz) {
  Matrix out = Matrix::Zero(w.cols(), dz.cols());
  if (has_direct_kernel(active_gemm_path()) && w.cols() >= kDirectMinRows &&
      dz.cols() >= kBlasMinColumns) {
    const Matrix wt = w.transpose();
    product(wt.data(), wt.rows(), wt.cols(), false, dz.data(), dz.rows(), dz.cols(), out.data());
    return out;
  }
  cblas_sgemm(CblasColMajor, CblasTrans, CblasNoTrans, static_cast<blasint>(w.cols()),
              static_cast<blasint>(dz.cols()), static_cast<blasint>(w.rows()), 1.0f, w.data(),
              static_cast<blasint>(w.rows()), dz.data(), static_cast<blasint>(w.rows()), 0.0f,
              out.data(), static_cast<blasint>(w.cols()));
  return out;
}

// The critic's pass in the DDPG update: 35 inputs, 3 x 256 ReLU, batch 256, parameter
// gradients from the first 128 samples, with the bias, ReLU and ReLU derivative fused into
// the kernel on a kernel path.
TEST(NetworkGemm, AWholeNetworkMatchesTheUnfusedPassOnThisPath) {
  SCOPED_TRACE(std::string("GEMM path ") + std::string(gemm_path_name(active_gemm_path())));
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
    product(w.data(), w.rows(), w.cols(), false, in->data(), w.cols(), n, z.data());
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
    product(grad_z.data(), w.rows(), wc, true, input.data(), w.cols(), w.cols(),
            expected_grads.data() + offset(w.data()));
    VectorMap(expected_grads.data() + offset(net.bias(l).data()), w.rows()) +=
        grad_z.leftCols(wc).rowwise().sum();
    (l == 0 ? expected_dx : upstream) = input_gradient(w, grad_z);
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
