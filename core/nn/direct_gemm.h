#pragma once
// Matrix products whose left operand is used as stored (column-major, not transposed),
// computed straight from the operands with no packing. OpenBLAS copies both operands into
// packed panels on every call, ~13% of the DDPG update; here A's register-high panels are
// read in place (contiguous down each column) and B's elements are broadcast from where
// they lie, so the only memory traffic is the operands themselves.
//
// Each output element is one sequential fused multiply-add chain over k from zero, then
// added to C (or to the bias, or to zero) once. That order is the project's definition,
// pinned bit for bit against a scalar reference in the tests on every path, so the AVX-512
// and AVX2 kernels give the same bits. It is also OpenBLAS's order in its SkylakeX kernel
// for k within one of its blocks, so there the kernels equal OpenBLAS bit for bit; other
// OpenBLAS kernels (Haswell, Zen) sum in another order and agree within rounding.

#include <cstddef>

#include "nn/gemm_path.h"

namespace pnp::nn {

struct DirectGemmOperands {
  std::ptrdiff_t m = 0, n = 0, k = 0;
  const float* a = nullptr;  // m x k, column-major, leading dimension m
  // B(p, j) is b[p * b_row_stride + j * b_col_stride]: (1, k) for a column-major k x n
  // matrix, (n, 1) for the transpose of a column-major n x k one.
  const float* b = nullptr;
  std::ptrdiff_t b_row_stride = 1, b_col_stride = 0;
  float* c = nullptr;       // m x n, column-major, leading dimension m
  bool accumulate = false;  // C += A B instead of C = A B
  // C = A B + bias, the m-vector added to every column (instead of accumulate).
  const float* row_bias = nullptr;
  bool relu = false;  // then C = max(C, 0), NaN kept (as Eigen's cwiseMax(0))
  // Then C = C where relu_output > 0, else 0 (m x n like C): the ReLU derivative of the
  // layer whose output this is, applied as the input gradient is stored.
  const float* relu_output = nullptr;
};

// True for the paths with an unpacked kernel (avx512, avx2); openblas has none.
bool has_direct_kernel(GemmPath path);

// C (+)= A B on `path`'s kernel. The path must have a kernel this CPU can run.
void direct_gemm(GemmPath path, const DirectGemmOperands& op);

// dst (cols x rows) = src (rows x cols)^T, both contiguous column-major, square tiles
// transposed in registers: the kernel's A for a product with a transposed left operand.
// The path must have a kernel this CPU can run.
void direct_transpose(GemmPath path, const float* src, std::ptrdiff_t rows, std::ptrdiff_t cols,
                      float* dst);

}  // namespace pnp::nn
