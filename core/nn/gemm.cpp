#include "nn/gemm.h"

#include <cblas.h>

#include "common/error.h"
#include "nn/direct_gemm.h"

namespace pnp::nn {
namespace {

// Whether C (m x n) = op(A) op(B) goes to the unpacked kernel: A as stored, at least one
// full register panel of rows, a batch wide enough to be worth it, and a kernel on this
// process's path.
bool use_direct(bool transpose_a, Eigen::Index m, Eigen::Index n) {
  return !transpose_a && m >= kDirectMinRows && n >= kBlasMinColumns &&
         has_direct_kernel(active_gemm_path());
}

DirectGemmOperands direct_operands(Eigen::Index m, Eigen::Index n, Eigen::Index k, const float* a,
                                   bool transpose_b, const float* b, Eigen::Index b_rows, float* c,
                                   bool accumulate) {
  DirectGemmOperands op{.m = m, .n = n, .k = k, .a = a, .b = b, .c = c, .accumulate = accumulate};
  op.b_row_stride = transpose_b ? b_rows : 1;
  op.b_col_stride = transpose_b ? 1 : b_rows;
  return op;
}

}  // namespace

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
  if (use_direct(ta, m, n) && alpha == 1.0f && (beta == 0.0f || beta == 1.0f)) {
    direct_gemm(active_gemm_path(),
                direct_operands(m, n, k, a, tb, b, b_rows, dst.data(), beta == 1.0f));
    return;
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

void gemm_bias(const float* w, Eigen::Index m, Eigen::Index k, const Matrix& x, const float* bias,
               bool relu, Matrix& dst) {
  if (x.rows() != k) throw_internal("gemm_bias: inner dimensions differ");
  const Eigen::Index n = x.cols();
  ensure_shape(dst, m, n);
  if (use_direct(false, m, n)) {
    DirectGemmOperands op = direct_operands(m, n, k, w, false, x.data(), k, dst.data(), false);
    op.row_bias = bias;
    op.relu = relu;
    direct_gemm(active_gemm_path(), op);
    return;
  }
  // The product accumulates onto the broadcast bias: one pass over dst instead of a
  // zeroing pass and a bias pass.
  const ConstVectorMap b(bias, m);
  for (Eigen::Index c = 0; c < n; ++c) dst.col(c) = b;  // vectorised, unlike colwise()
  gemm(false, false, 1.0f, w, m, k, x.data(), k, n, 1.0f, dst);
  if (relu) dst = dst.cwiseMax(0.0f);
}

void gemm_input_gradient(const float* w, Eigen::Index m, Eigen::Index k, const Matrix& dz,
                         const Matrix* relu_output, Matrix& scratch, Matrix& dst) {
  if (dz.rows() != m) throw_internal("gemm_input_gradient: inner dimensions differ");
  const Eigen::Index n = dz.cols();
  if (relu_output && (relu_output->rows() != k || relu_output->cols() != n))
    throw_internal("gemm_input_gradient: ReLU output of the wrong shape");
  if (!use_direct(false, k, n)) {
    gemm(true, false, 1.0f, w, m, k, dz.data(), m, n, 0.0f, dst);
    if (relu_output) dst = (relu_output->array() > 0.0f).select(dst.array(), 0.0f);
    return;
  }
  ensure_shape(scratch, k, m);
  direct_transpose(active_gemm_path(), w, m, k, scratch.data());
  ensure_shape(dst, k, n);
  DirectGemmOperands op =
      direct_operands(k, n, m, scratch.data(), false, dz.data(), m, dst.data(), false);
  op.relu_output = relu_output ? relu_output->data() : nullptr;
  direct_gemm(active_gemm_path(), op);
}

void gemm_accumulate(bool ta, bool tb, const float* a, Eigen::Index a_rows, Eigen::Index a_cols,
                     const float* b, Eigen::Index b_rows, Eigen::Index b_cols, float* dst) {
  const Eigen::Index m = ta ? a_cols : a_rows, k = ta ? a_rows : a_cols;
  const Eigen::Index kb = tb ? b_cols : b_rows, n = tb ? b_rows : b_cols;
  if (k != kb) throw_internal("gemm_accumulate: inner dimensions differ");
  if (use_direct(ta, m, n)) {
    direct_gemm(active_gemm_path(), direct_operands(m, n, k, a, tb, b, b_rows, dst, true));
    return;
  }
  cblas_sgemm(CblasColMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans,
              static_cast<blasint>(m), static_cast<blasint>(n), static_cast<blasint>(k), 1.0f, a,
              static_cast<blasint>(a_rows), b, static_cast<blasint>(b_rows), 1.0f, dst,
              static_cast<blasint>(m));
}

}  // namespace pnp::nn
