#include "nn/gemm.h"

#include <cblas.h>

#include "common/error.h"

namespace pnp::nn {

void gemm(bool ta, bool tb, float alpha, const float* a, Eigen::Index a_rows, Eigen::Index a_cols,
          const float* b, Eigen::Index b_rows, Eigen::Index b_cols, float beta, Matrix& dst) {
  const Eigen::Index m = ta ? a_cols : a_rows, k = ta ? a_rows : a_cols;
  const Eigen::Index kb = tb ? b_cols : b_rows, n = tb ? b_rows : b_cols;
  if (k != kb) throw_internal("gemm: inner dimensions differ");
  if (beta == 0.0f) {
    ensure_shape(dst, m, n);
  } else if (dst.rows() != m || dst.cols() != n) {
    throw_internal("gemm: accumulating into a matrix of the wrong shape");
  }
  if (n == 1 && !tb && m >= kBlasMinColumns * 16) {
    // One sample through a wide layer (acting, serving): a matrix-vector product.
    cblas_sgemv(CblasColMajor, ta ? CblasTrans : CblasNoTrans, static_cast<blasint>(a_rows),
                static_cast<blasint>(a_cols), alpha, a, static_cast<blasint>(a_rows), b, 1, beta,
                dst.data(), 1);
    return;
  }
  if (n >= kBlasMinColumns || m >= kBlasMinColumns * 16) {
    cblas_sgemm(CblasColMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans,
                static_cast<blasint>(m), static_cast<blasint>(n), static_cast<blasint>(k), alpha, a,
                static_cast<blasint>(a_rows), b, static_cast<blasint>(b_rows), beta, dst.data(),
                static_cast<blasint>(m));
    return;
  }
  const ConstMatrixMap A(a, a_rows, a_cols), B(b, b_rows, b_cols);
  if (beta == 0.0f)
    dst.setZero();
  else if (beta != 1.0f)
    dst *= beta;
  if (!ta && !tb)
    dst.noalias() += alpha * A * B;
  else if (ta && !tb)
    dst.noalias() += alpha * A.transpose() * B;
  else if (!ta && tb)
    dst.noalias() += alpha * A * B.transpose();
  else
    dst.noalias() += alpha * A.transpose() * B.transpose();
}

void gemm_accumulate(bool ta, bool tb, const float* a, Eigen::Index a_rows, Eigen::Index a_cols,
                     const float* b, Eigen::Index b_rows, Eigen::Index b_cols, float* dst) {
  const Eigen::Index m = ta ? a_cols : a_rows, k = ta ? a_rows : a_cols;
  const Eigen::Index kb = tb ? b_cols : b_rows, n = tb ? b_rows : b_cols;
  if (k != kb) throw_internal("gemm_accumulate: inner dimensions differ");
  cblas_sgemm(CblasColMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans,
              static_cast<blasint>(m), static_cast<blasint>(n), static_cast<blasint>(k), 1.0f, a,
              static_cast<blasint>(a_rows), b, static_cast<blasint>(b_rows), 1.0f, dst,
              static_cast<blasint>(m));
}

}  // namespace pnp::nn
