#pragma once
// float32 column-major matrices; a batch is stored one sample per column, so a dense
// layer is one GEMM: Y = W X + b.

#include <Eigen/Core>
#include <vector>

namespace pnp::nn {

using Matrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic>;
using Vector = Eigen::Matrix<float, Eigen::Dynamic, 1>;
using MatrixMap = Eigen::Map<Matrix>;
using ConstMatrixMap = Eigen::Map<const Matrix>;
using VectorMap = Eigen::Map<Vector>;
using ConstVectorMap = Eigen::Map<const Vector>;
using MatrixRef = Eigen::Ref<const Matrix>;

// Flat parameter and gradient storage. Eigen's vectorised kernels peel a number of
// leading elements that depends on the buffer's alignment, which changes the order of
// floating-point sums: with the heap's arbitrary 16-byte alignment, identical runs in one
// process gave different weights. Aligned storage makes every run bit-identical.
using AlignedFloats = std::vector<float, Eigen::aligned_allocator<float>>;

// Resizes only when the shape changes, so a steady batch size never allocates.
inline void ensure_shape(Matrix& m, Eigen::Index rows, Eigen::Index cols) {
  if (m.rows() != rows || m.cols() != cols) m.resize(rows, cols);
}

}  // namespace pnp::nn
