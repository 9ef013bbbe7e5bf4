#pragma once
// C = alpha op(A) op(B) + beta C for column-major float matrices. Batched products (the
// DDPG update's 128-column partitions) go to OpenBLAS pinned to one thread, about 1.8x
// Eigen's own kernel here; narrow ones (one sample when acting) stay in Eigen, which is
// faster at that size; a single sample through a wide layer is a matrix-vector product
// (SGEMV). The update's two partitions call OpenBLAS from two threads at
// once; the reproducibility tests cover that.

#include "nn/tensor.h"

namespace pnp::nn {

inline constexpr Eigen::Index kBlasMinColumns = 16;

// dst = alpha * op(a) * op(b) + beta * dst; dst must already have the result's shape
// when beta != 0. `a` and `b` are contiguous column-major storage.
void gemm(bool transpose_a, bool transpose_b, float alpha, const float* a, Eigen::Index a_rows,
          Eigen::Index a_cols, const float* b, Eigen::Index b_rows, Eigen::Index b_cols, float beta,
          Matrix& dst);

// dst(m x n, column-major, contiguous) += op(a) * op(b), through OpenBLAS: accumulates a
// batched product straight into a gradient buffer.
void gemm_accumulate(bool transpose_a, bool transpose_b, const float* a, Eigen::Index a_rows,
                     Eigen::Index a_cols, const float* b, Eigen::Index b_rows, Eigen::Index b_cols,
                     float* dst);

}  // namespace pnp::nn
