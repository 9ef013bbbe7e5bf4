#include "nn/lstm_cell.h"

#include <cmath>
#include <string>

#include "common/error.h"
#include "nn/blas_threads.h"

namespace pnp::nn {

LstmCell::LstmCell(int inputs, int hidden) : inputs_(inputs), hidden_(hidden) {
  pin_blas_to_one_thread();
  if (inputs <= 0)
    throw_invalid_argument("lstm inputs", "a positive width", std::to_string(inputs));
  if (hidden <= 0)
    throw_invalid_argument("lstm hidden", "a positive width", std::to_string(hidden));
  u_offset_ = static_cast<std::size_t>(4 * hidden * inputs);
  b_offset_ = u_offset_ + static_cast<std::size_t>(4 * hidden * hidden);
  params_.assign(b_offset_ + static_cast<std::size_t>(4 * hidden), 0.0f);
  grads_.assign(params_.size(), 0.0f);
}

void LstmCell::zero_grads() {
  std::fill(grads_.begin(), grads_.end(), 0.0f);
}

void LstmCell::initialise(Rng& rng) {
  const double bound = 1.0 / std::sqrt(static_cast<double>(hidden_));
  for (float& p : params_) p = static_cast<float>(rng.uniform(-bound, bound));
}

void LstmCell::forward(const MatrixRef& x, const MatrixRef& h_prev, const MatrixRef& c_prev,
                       LstmStepCache& cache, Matrix& h) const {
  const Eigen::Index H = hidden_, n = x.cols();
  cache.x = x;
  cache.h_prev = h_prev;
  cache.c_prev = c_prev;
  ensure_shape(cache.gates, 4 * H, n);
  cache.gates.noalias() = w() * x;
  cache.gates.noalias() += u() * h_prev;
  cache.gates.colwise() += b();
  auto sigmoid = [](auto v) { return 1.0f / (1.0f + (-v).exp()); };
  cache.gates.topRows(2 * H) = sigmoid(cache.gates.topRows(2 * H).array());
  cache.gates.middleRows(2 * H, H) = cache.gates.middleRows(2 * H, H).array().tanh();
  cache.gates.bottomRows(H) = sigmoid(cache.gates.bottomRows(H).array());
  const auto i = cache.gates.topRows(H).array();
  const auto f = cache.gates.middleRows(H, H).array();
  const auto g = cache.gates.middleRows(2 * H, H).array();
  const auto o = cache.gates.bottomRows(H).array();
  cache.c = f * c_prev.array() + i * g;
  cache.tanh_c = cache.c.array().tanh();
  h = o * cache.tanh_c.array();
}

void LstmCell::backward(const LstmStepCache& cache, const MatrixRef& dh, const MatrixRef& dc,
                        Matrix* dx, Matrix& dh_prev, Matrix& dc_prev) {
  const Eigen::Index H = hidden_, n = dh.cols();
  const auto i = cache.gates.topRows(H).array();
  const auto f = cache.gates.middleRows(H, H).array();
  const auto g = cache.gates.middleRows(2 * H, H).array();
  const auto o = cache.gates.bottomRows(H).array();
  const auto tc = cache.tanh_c.array();
  // Total gradient reaching c: through h (h = o tanh c) and directly.
  const Matrix dc_total = (dc.array() + dh.array() * o * (1.0f - tc.square())).matrix();
  ensure_shape(dgates_, 4 * H, n);
  dgates_.topRows(H) = (dc_total.array() * g * i * (1.0f - i)).matrix();
  dgates_.middleRows(H, H) = (dc_total.array() * cache.c_prev.array() * f * (1.0f - f)).matrix();
  dgates_.middleRows(2 * H, H) = (dc_total.array() * i * (1.0f - g.square())).matrix();
  dgates_.bottomRows(H) = (dh.array() * tc * o * (1.0f - o)).matrix();

  MatrixMap dw(grads_.data(), 4 * H, inputs_);
  MatrixMap du(grads_.data() + u_offset_, 4 * H, H);
  VectorMap db(grads_.data() + b_offset_, 4 * H);
  dw.noalias() += dgates_ * cache.x.transpose();
  du.noalias() += dgates_ * cache.h_prev.transpose();
  db += dgates_.rowwise().sum();
  if (dx) {
    ensure_shape(*dx, inputs_, n);
    dx->noalias() = w().transpose() * dgates_;
  }
  ensure_shape(dh_prev, H, n);
  dh_prev.noalias() = u().transpose() * dgates_;
  dc_prev = (dc_total.array() * f).matrix();
}

}  // namespace pnp::nn
