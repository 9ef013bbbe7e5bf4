#pragma once
// The arithmetic the unpacked kernels promise (nn/direct_gemm.h), written the plainest
// way: one fused multiply-add chain over k from zero per element, then one addition to C
// (or to the bias, or to zero), then the ReLU and the ReLU-derivative mask. Every kernel
// path must give exactly these bits on every CPU.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "nn/direct_gemm.h"

namespace pnp::testing {

inline std::vector<float> reference_gemm(const nn::DirectGemmOperands& op, std::vector<float> c) {
  for (std::ptrdiff_t j = 0; j < op.n; ++j) {
    for (std::ptrdiff_t i = 0; i < op.m; ++i) {
      float acc = 0.0f;
      for (std::ptrdiff_t p = 0; p < op.k; ++p)
        acc = std::fma(op.a[i + p * op.m], op.b[p * op.b_row_stride + j * op.b_col_stride], acc);
      float& out = c[static_cast<std::size_t>(i + j * op.m)];
      out = op.accumulate ? out + acc : (op.row_bias ? op.row_bias[i] : 0.0f) + acc;
      if (op.relu) out = std::max(out, 0.0f);
      if (op.relu_output && !(op.relu_output[i + j * op.m] > 0.0f)) out = 0.0f;
    }
  }
  return c;
}

// sum_p |A(i,p) B(p,j)| + |C(i,j)| (or |bias(i)|) per element, in double: the scale of
// the rounding error bound of any summation order.
inline std::vector<double> absolute_gemm(const nn::DirectGemmOperands& op,
                                         const std::vector<float>& c) {
  std::vector<double> out(c.size());
  for (std::ptrdiff_t j = 0; j < op.n; ++j) {
    for (std::ptrdiff_t i = 0; i < op.m; ++i) {
      double acc = 0.0;
      for (std::ptrdiff_t p = 0; p < op.k; ++p)
        acc += std::abs(static_cast<double>(op.a[i + p * op.m]) *
                        static_cast<double>(op.b[p * op.b_row_stride + j * op.b_col_stride]));
      const auto e = static_cast<std::size_t>(i + j * op.m);
      out[e] = acc + std::abs(op.accumulate ? static_cast<double>(c[e])
                              : op.row_bias ? static_cast<double>(op.row_bias[i])
                                            : 0.0);
    }
  }
  return out;
}

}  // namespace pnp::testing
