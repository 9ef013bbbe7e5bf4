#include "nn/mlp.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "support/allocation_counter.h"

namespace pnp::nn {
namespace {

// Loss = sum(w .* y) for a fixed random w: dL/dy = w.
double loss(Mlp& net, const Matrix& x, const Matrix& w) {
  MlpWorkspace ws;
  return static_cast<double>((net.forward(x, ws).array() * w.array()).sum());
}

// Signs of every pre-activation (those of the activations: f(z) > 0 exactly when z > 0):
// a finite difference is only valid if no unit crosses a ReLU kink between the two
// evaluations.
std::vector<bool> pattern(Mlp& net, const Matrix& x) {
  MlpWorkspace ws;
  net.forward(x, ws);
  std::vector<bool> signs;
  for (const Matrix& z : ws.post) {
    for (Eigen::Index i = 0; i < z.size(); ++i) signs.push_back(z.data()[i] > 0);
  }
  return signs;
}

void gradient_check(Activation hidden, Activation output) {
  Rng rng(3);
  Mlp net({5, {7, 6}, 3, hidden, output});
  net.initialise(rng);
  Matrix x = Matrix::Random(5, 4);
  const Matrix w = Matrix::Random(3, 4);
  MlpWorkspace ws;
  net.forward(x, ws);
  net.zero_grads();
  Matrix dx;
  net.backward(ws, w, true, &dx);
  const std::vector<float> analytic(net.grads().begin(), net.grads().end());
  const float eps = 1e-2f;
  int checked = 0, considered = 0;
  const auto base = pattern(net, x);
  for (std::size_t i = 0; i < net.params().size(); i += 3) {
    const float saved = net.params()[i];
    net.params()[i] = saved + eps;
    const double up = loss(net, x, w);
    const bool same_up = pattern(net, x) == base;
    net.params()[i] = saved - eps;
    const double down = loss(net, x, w);
    const bool same_down = pattern(net, x) == base;
    net.params()[i] = saved;
    ++considered;
    if (!same_up || !same_down) continue;
    const double numeric = (up - down) / (2.0 * static_cast<double>(eps));
    EXPECT_NEAR(analytic[i], numeric, 2e-3 + 2e-2 * std::abs(numeric)) << "param " << i;
    ++checked;
  }
  EXPECT_GT(checked, considered * 3 / 4) << "too many parameters sit on a kink";
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const float saved = x(r, 1);
    x(r, 1) = saved + eps;
    const double up = loss(net, x, w);
    const bool same_up = pattern(net, x) == base;
    x(r, 1) = saved - eps;
    const double down = loss(net, x, w);
    const bool same_down = pattern(net, x) == base;
    x(r, 1) = saved;
    if (!same_up || !same_down) continue;
    EXPECT_NEAR(dx(r, 1), (up - down) / (2.0 * static_cast<double>(eps)),
                2e-3 + 2e-2 * std::abs((up - down) / (2.0 * static_cast<double>(eps))));
  }
}

TEST(Mlp, GradientsMatchFiniteDifferencesRelu) {
  gradient_check(Activation::kReLU, Activation::kNone);
}
TEST(Mlp, GradientsMatchFiniteDifferencesTanhHead) {
  gradient_check(Activation::kReLU, Activation::kTanh);
}
TEST(Mlp, GradientsMatchFiniteDifferencesElu) {
  gradient_check(Activation::kELU, Activation::kNone);
}

TEST(Mlp, ParameterLayoutAndForwardMatchAHandComputation) {
  Mlp net({2, {}, 1, Activation::kReLU, Activation::kTanh});
  net.params()[0] = 0.5f;  // W (1x2), column-major
  net.params()[1] = -1.0f;
  net.params()[16] = 0.25f;  // bias starts on the next 16-float boundary
  MlpWorkspace ws;
  Matrix x(2, 1);
  x << 2.0f, 0.5f;
  EXPECT_NEAR(net.forward(x, ws)(0, 0), std::tanh(0.5f * 2 - 0.5f + 0.25f), 1e-6);
}

TEST(Mlp, SteadyBatchDoesNotReallocate) {
  Rng rng(1);
  Mlp net({4, {8}, 2});
  net.initialise(rng);
  MlpWorkspace ws;
  Matrix x = Matrix::Random(4, 16);
  net.forward(x, ws);
  const float* before = ws.post[0].data();
  net.forward(x, ws);
  EXPECT_EQ(ws.post[0].data(), before);
}

// Wide enough for the unpacked kernel, whose input gradient transposes each W into the
// workspace: one buffer per layer, so a steady batch allocates nothing after the first.
TEST(Mlp, SteadyBatchBackwardDoesNotReallocate) {
  Rng rng(2);
  Mlp net({35, {64, 64}, 1});
  net.initialise(rng);
  MlpWorkspace ws;
  const Matrix x = Matrix::Random(35, 32), dy = Matrix::Random(1, 32);
  AlignedFloats grads(net.params().size(), 0.0f);
  Matrix dx;
  const auto pass = [&] {
    net.forward(x, ws);
    net.backward_into(ws, dy, grads, &dx);
    std::vector<const float*> buffers{dx.data(), ws.grad_z.data()};
    for (const Matrix& m : ws.weight_t) buffers.push_back(m.data());
    for (const Matrix& m : ws.grad) buffers.push_back(m.data());
    return buffers;
  };
  const auto first = pass();
  EXPECT_EQ(pass(), first);
  // The addresses above catch a buffer that moved; the count catches one that was freed
  // and allocated again at the same address (glibc reuses it at once).
  if (test::counting_allocations()) {
    const std::size_t before = test::allocations_on_this_thread();
    net.forward(x, ws);
    net.backward_into(ws, dy, grads, &dx);
    EXPECT_EQ(test::allocations_on_this_thread() - before, 0u);
  }
}

// One pass over [A | B] with weight_columns = |A|: parameter gradients of A alone, input
// gradients of both (the DDPG update's merged critic pass).
TEST(Mlp, WeightColumnsLimitParameterGradientsButNotInputGradients) {
  Rng rng(9);
  Mlp net({5, {8, 8}, 1, Activation::kReLU, Activation::kNone});
  net.initialise(rng);
  Matrix x(5, 6), dy(1, 6);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = static_cast<float>(rng.normal());
  for (Eigen::Index i = 0; i < dy.size(); ++i) dy.data()[i] = static_cast<float>(rng.normal());

  MlpWorkspace merged;
  net.forward(x, merged);
  AlignedFloats merged_grads(net.params().size(), 0.0f);
  Matrix merged_dx;
  net.backward_into(merged, dy, merged_grads, &merged_dx, 4);

  MlpWorkspace first;
  net.forward(x.leftCols(4), first);
  AlignedFloats first_grads(net.params().size(), 0.0f);
  net.backward_into(first, dy.leftCols(4), first_grads, nullptr);
  MlpWorkspace all;
  net.forward(x, all);
  Matrix all_dx;
  net.backward_into(all, dy, {}, &all_dx);

  for (std::size_t k = 0; k < first_grads.size(); ++k)
    EXPECT_NEAR(merged_grads[k], first_grads[k], 1e-5f) << k;
  EXPECT_TRUE(merged_dx.isApprox(all_dx, 1e-6f));
}

// One sample goes through a matrix-vector product, a batch through GEMM: the same
// network must give the same outputs either way.
TEST(Mlp, OneSampleAndABatchAgree) {
  Rng rng(4);
  Mlp net({31, {256, 256}, 4, Activation::kReLU, Activation::kTanh});
  net.initialise(rng);
  Matrix batch(31, 32);
  for (Eigen::Index i = 0; i < batch.size(); ++i)
    batch.data()[i] = static_cast<float>(rng.normal());
  MlpWorkspace all, one;
  const Matrix batched = net.forward(batch, all);
  for (Eigen::Index c = 0; c < batch.cols(); ++c) {
    const Matrix single = net.forward(batch.col(c), one);
    EXPECT_TRUE(single.col(0).isApprox(batched.col(c), 1e-5f)) << "sample " << c;
  }
}

TEST(Mlp, RefusesBadShapes) {
  EXPECT_THROW(Mlp({0, {4}, 2}), Error);
  EXPECT_THROW(Mlp({3, {4, -1}, 2}), Error);
  Mlp net({3, {4}, 2});
  MlpWorkspace ws;
  EXPECT_THROW(net.forward(Matrix::Zero(5, 1), ws), Error);
}

}  // namespace
}  // namespace pnp::nn
