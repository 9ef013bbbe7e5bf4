#pragma once
// C = alpha op(A) op(B) + beta C for column-major float matrices. Batched products (the
// DDPG update's 256-column GEMMs) go to single-threaded OpenBLAS, about 1.8x Eigen's own
// kernel here; narrow ones (one sample when acting) stay in Eigen. OpenBLAS is only
// reached from the thread that trains: its pthread build is not safe to call from the
// rollout and evaluation threads at the same time (measured: runs stopped reproducing).

#include "nn/tensor.h"

namespace pnp::nn {

inline constexpr Eigen::Index kBlasMinColumns = 16;

// dst = alpha * op(a) * op(b) + beta * dst; dst must already have the result's shape
// when beta != 0. `a` and `b` are contiguous column-major storage.
void gemm(bool transpose_a, bool transpose_b, float alpha, const float* a, Eigen::Index a_rows,
          Eigen::Index a_cols, const float* b, Eigen::Index b_rows, Eigen::Index b_cols, float beta,
          Matrix& dst);

}  // namespace pnp::nn
