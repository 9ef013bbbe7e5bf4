#pragma once
// C = alpha op(A) op(B) + beta C for column-major float matrices. Batched products with
// a full register panel of rows (the DDPG update's layers) go to the unpacked kernel of
// the process's GEMM path (nn/gemm_path.h: AVX-512 or AVX2, picked at run time), ~25%
// faster over the update than OpenBLAS because nothing is packed; the rest, and every
// product on the openblas path, go to OpenBLAS pinned to one thread (about 1.8x
// Eigen's own kernel here); narrow ones (one sample when acting) stay in Eigen, which is
// faster at that size, and a single sample through a wide layer is a matrix-vector
// product (SGEMV). The update's two partitions call these from two threads at once; the
// reproducibility tests cover that.

#include "nn/tensor.h"

namespace pnp::nn {

inline constexpr Eigen::Index kBlasMinColumns = 16;
// Products with A as stored (W^T is transposed into scratch first), at least this many
// rows, at least kBlasMinColumns columns, alpha 1 and beta 0 or 1 use the unpacked kernel
// (nn/direct_gemm.h) when the process's path has one.
inline constexpr Eigen::Index kDirectMinRows = 32;

// dst = alpha * op(a) * op(b) + beta * dst; dst must already have the result's shape
// when beta != 0. `a` and `b` are contiguous column-major storage.
void gemm(bool transpose_a, bool transpose_b, float alpha, const float* a, Eigen::Index a_rows,
          Eigen::Index a_cols, const float* b, Eigen::Index b_rows, Eigen::Index b_cols, float beta,
          Matrix& dst);

// dst = W x + bias (added to every column), then max(dst, 0) if relu: a dense layer.
// W is m x k and x is k x n, both contiguous column-major.
void gemm_bias(const float* w, Eigen::Index m, Eigen::Index k, const Matrix& x, const float* bias,
               bool relu, Matrix& dst);

// dst = W^T dz, the input gradient of a dense layer whose W is m x k; with relu_output
// (k x n, the layer below's ReLU output), times that ReLU's derivative, so dst is the layer
// below's dL/dz. For the unpacked kernel W^T is first copied into `scratch` (a copy is
// cheaper than OpenBLAS's packing).
void gemm_input_gradient(const float* w, Eigen::Index m, Eigen::Index k, const Matrix& dz,
                         const Matrix* relu_output, Matrix& scratch, Matrix& dst);

// dst(m x n, column-major, contiguous) += op(a) * op(b): accumulates a batched product
// straight into a gradient buffer (the unpacked kernel, or OpenBLAS).
void gemm_accumulate(bool transpose_a, bool transpose_b, const float* a, Eigen::Index a_rows,
                     Eigen::Index a_cols, const float* b, Eigen::Index b_rows, Eigen::Index b_cols,
                     float* dst);

}  // namespace pnp::nn
