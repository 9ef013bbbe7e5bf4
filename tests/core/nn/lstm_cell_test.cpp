#include "nn/lstm_cell.h"

#include <gtest/gtest.h>

#include <vector>

namespace pnp::nn {
namespace {

// Runs T steps from zero state; loss = sum_t sum(w_t .* h_t).
double unroll(const LstmCell& cell, const std::vector<Matrix>& xs, const std::vector<Matrix>& ws,
              std::vector<LstmStepCache>* caches = nullptr) {
  Matrix h = Matrix::Zero(cell.hidden(), xs[0].cols()), c = h, h_next;
  double loss = 0;
  std::vector<LstmStepCache> local(xs.size());
  auto& cs = caches ? *caches : local;
  cs.resize(xs.size());
  for (std::size_t t = 0; t < xs.size(); ++t) {
    cell.forward(xs[t], h, c, cs[t], h_next);
    c = cs[t].c;
    h = h_next;
    loss += static_cast<double>((h.array() * ws[t].array()).sum());
  }
  return loss;
}

TEST(LstmCell, BackpropagationThroughTimeMatchesFiniteDifferences) {
  Rng rng(11);
  LstmCell cell(3, 4);
  cell.initialise(rng);
  std::vector<Matrix> xs, ws;
  for (int t = 0; t < 4; ++t) {
    xs.push_back(Matrix::Random(3, 2));
    ws.push_back(Matrix::Random(4, 2));
  }
  std::vector<LstmStepCache> caches;
  unroll(cell, xs, ws, &caches);
  cell.zero_grads();
  Matrix dh_next = Matrix::Zero(4, 2), dc_next = Matrix::Zero(4, 2), dh_prev, dc_prev;
  std::vector<Matrix> dxs(xs.size());
  for (std::size_t t = xs.size(); t-- > 0;) {
    const Matrix dh = dh_next + ws[t];
    cell.backward(caches[t], dh, dc_next, &dxs[t], dh_prev, dc_prev);
    dh_next = dh_prev;
    dc_next = dc_prev;
  }
  const std::vector<float> analytic(cell.grads().begin(), cell.grads().end());
  const float eps = 1e-2f;
  for (std::size_t i = 0; i < cell.params().size(); i += 2) {
    const float saved = cell.params()[i];
    cell.params()[i] = saved + eps;
    const double up = unroll(cell, xs, ws);
    cell.params()[i] = saved - eps;
    const double down = unroll(cell, xs, ws);
    cell.params()[i] = saved;
    const double numeric = (up - down) / (2.0 * static_cast<double>(eps));
    EXPECT_NEAR(analytic[i], numeric, 2e-3 + 2e-2 * std::abs(numeric)) << "param " << i;
  }
  // Input gradient at the first step flows through all later steps.
  for (Eigen::Index r = 0; r < 3; ++r) {
    const float saved = xs[0](r, 0);
    xs[0](r, 0) = saved + eps;
    const double up = unroll(cell, xs, ws);
    xs[0](r, 0) = saved - eps;
    const double down = unroll(cell, xs, ws);
    xs[0](r, 0) = saved;
    EXPECT_NEAR(dxs[0](r, 0), (up - down) / (2.0 * static_cast<double>(eps)), 2e-3);
  }
}

}  // namespace
}  // namespace pnp::nn
