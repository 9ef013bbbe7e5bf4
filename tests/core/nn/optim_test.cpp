#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "common/error.h"
#include "nn/adam.h"
#include "nn/flat_ops.h"
#include "nn/normalizer.h"

namespace pnp::nn {
namespace {

TEST(Adam, FirstStepMovesEachParameterByTheLearningRate) {
  std::vector<float> p{1.0f, -2.0f}, g{0.5f, -3.0f};
  Adam adam(2, {0.1, 0.9, 0.999, 1e-8});
  adam.step(p, g);
  // With bias correction the first step is lr * sign(g).
  EXPECT_NEAR(p[0], 0.9f, 1e-5);
  EXPECT_NEAR(p[1], -1.9f, 1e-5);
}

TEST(Adam, MinimisesAQuadratic) {
  std::vector<float> p{3.0f, -4.0f}, g(2);
  Adam adam(2, {0.05});
  for (int i = 0; i < 2000; ++i) {
    g[0] = 2 * p[0];
    g[1] = 2 * (p[1] - 1.0f);
    adam.step(p, g);
  }
  EXPECT_NEAR(p[0], 0.0f, 1e-2);
  EXPECT_NEAR(p[1], 1.0f, 1e-2);
}

TEST(Adam, AStepAppliedInSlicesEqualsOneStep) {
  // Slices begin on the alignment; the length is not a multiple of it (a scalar tail).
  const std::size_t n = 1001;
  std::vector<float, Eigen::aligned_allocator<float>> whole(n), sliced(n), g(n);  // as Mlp's
  for (std::size_t i = 0; i < n; ++i) {
    whole[i] = sliced[i] = std::sin(static_cast<float>(i));
    g[i] = std::cos(0.37f * static_cast<float>(i));
  }
  Adam one(n, {0.01}), parts(n, {0.01});
  for (int step = 0; step < 3; ++step) {
    one.step(whole, g);
    parts.begin_step();
    parts.apply(sliced, g, 0, 20 * kSliceAlignment);
    parts.apply(sliced, g, 20 * kSliceAlignment, kSliceAlignment);
    parts.apply(sliced, g, 21 * kSliceAlignment, n - 21 * kSliceAlignment);
  }
  EXPECT_EQ(whole, sliced);
  EXPECT_EQ(one.steps(), parts.steps());
}

TEST(Adam, PartialGradientsAreSummedInOrderBeforeTheStep) {
  // Longer than Adam's internal chunk, with a scalar tail.
  const std::size_t n = 1500;
  std::vector<float, Eigen::aligned_allocator<float>> summed(n), partial(n), g0(n), g1(n), g(n);
  for (std::size_t i = 0; i < n; ++i) {
    summed[i] = partial[i] = std::sin(static_cast<float>(i));
    g0[i] = std::cos(0.37f * static_cast<float>(i));
    g1[i] = 0.5f * std::sin(1.3f * static_cast<float>(i));
    g[i] = g0[i] + g1[i];
  }
  Adam one(n, {0.01}), parts(n, {0.01});
  const std::array<std::span<const float>, 2> partials{g0, g1};
  for (int step = 0; step < 3; ++step) {
    one.step(summed, g);
    parts.begin_step();
    parts.apply(partial, partials, 0, 40 * kSliceAlignment);
    parts.apply(partial, partials, 40 * kSliceAlignment, n - 40 * kSliceAlignment);
  }
  EXPECT_EQ(summed, partial);  // bit for bit
}

TEST(Adam, RefusesInvalidHyperparameters) {
  try {
    Adam(3, {-1e-3});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("adam.learning_rate: expected a positive finite number"),
              std::string::npos);
  }
  EXPECT_THROW(Adam(3, {1e-3, 1.0}), Error);
}

TEST(FlatOps, PolyakAndClipping) {
  std::vector<float> target{1.0f, 1.0f}, source{0.0f, 2.0f};
  polyak_update(target, source, 0.95);
  EXPECT_NEAR(target[0], 0.95f, 1e-6);
  EXPECT_NEAR(target[1], 1.05f, 1e-6);
  std::vector<float> g{3.0f, 4.0f};
  EXPECT_NEAR(clip_grad_norm(g, 1.0), 5.0, 1e-6);
  EXPECT_NEAR(l2_norm(g), 1.0, 1e-6);
  EXPECT_NEAR(clip_grad_norm(g, 10.0), 1.0, 1e-6);  // below the limit: unchanged
  EXPECT_NEAR(g[0], 0.6f, 1e-6);
}

TEST(Normalizer, RunningStatisticsClipAndStdFloor) {
  Normalizer norm(2, 5.0, 0.01);
  for (int i = 0; i < 1000; ++i) {
    const double sample[2] = {10.0 + (i % 2 ? 1.0 : -1.0), 3.0};  // mean 10 std 1; constant
    norm.update(sample);
  }
  norm.refresh();
  EXPECT_NEAR(norm.mean()[0], 10.0f, 1e-5);
  EXPECT_NEAR(norm.stddev()[0], 1.0f, 1e-5);
  EXPECT_NEAR(norm.stddev()[1], 0.01f, 1e-6);  // the floor
  Matrix out(2, 1);
  const double x[2] = {12.0, 3.5};
  norm.normalize_into(x, out, 0, 0);
  EXPECT_NEAR(out(0, 0), 2.0f, 1e-5);
  EXPECT_EQ(out(1, 0), 5.0f);  // (0.5 / 0.01) clipped to 5
}

}  // namespace
}  // namespace pnp::nn
