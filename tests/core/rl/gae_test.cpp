#include "rl/gae.h"

#include <gtest/gtest.h>

#include <vector>

namespace pnp::rl {
namespace {

TEST(Gae, MatchesAHandComputedCase) {
  // gamma 0.9, lambda 0.5; rewards 0, 0, 1; values 0.5, 0.6, 0.7; terminal.
  const std::vector<double> r{0, 0, 1}, v{0.5, 0.6, 0.7};
  const Advantages a = compute_gae(r, v, 0.0, 0.9, 0.5);
  // deltas: d2 = 1 - 0.7 = 0.3; d1 = 0 + 0.9*0.7 - 0.6 = 0.03; d0 = 0.9*0.6 - 0.5 = 0.04
  // A2 = 0.3; A1 = 0.03 + 0.45*0.3 = 0.165; A0 = 0.04 + 0.45*0.165 = 0.11425
  EXPECT_NEAR(a.advantages[2], 0.3, 1e-12);
  EXPECT_NEAR(a.advantages[1], 0.165, 1e-12);
  EXPECT_NEAR(a.advantages[0], 0.11425, 1e-12);
  EXPECT_NEAR(a.returns[0], 0.61425, 1e-12);
}

TEST(Gae, LambdaOneGivesDiscountedReturnsMinusValues) {
  const std::vector<double> r{1, 2, 3}, v{0.1, 0.2, 0.3};
  const Advantages a = compute_gae(r, v, 0.5, 0.9, 1.0);
  const double g2 = 3 + 0.9 * 0.5, g1 = 2 + 0.9 * g2, g0 = 1 + 0.9 * g1;
  EXPECT_NEAR(a.returns[0], g0, 1e-12);
  EXPECT_NEAR(a.returns[1], g1, 1e-12);
  EXPECT_NEAR(a.advantages[2], g2 - 0.3, 1e-12);
}

TEST(Gae, PerStepDiscountsMatchAHandComputedSemiMarkovCase) {
  // Decisions that ran 2 and 3 environment steps at gamma 0.9 per step; lambda 1:
  // returns are r0 + 0.81 (r1 + 0.729 * bootstrap).
  const std::vector<double> r{0, 1}, v{0.2, 0.4}, discounts{0.81, 0.729};
  const Advantages a = compute_gae(r, v, 0.5, discounts, 1.0);
  const double g1 = 1 + 0.729 * 0.5, g0 = 0 + 0.81 * g1;
  EXPECT_NEAR(a.returns[1], g1, 1e-12);
  EXPECT_NEAR(a.returns[0], g0, 1e-12);
  EXPECT_NEAR(a.advantages[0], g0 - 0.2, 1e-12);
}

TEST(Gae, ConstantDiscountsEqualTheScalarForm) {
  const std::vector<double> r{0, 0, 1}, v{0.5, 0.6, 0.7}, discounts{0.9, 0.9, 0.9};
  const Advantages a = compute_gae(r, v, 0.0, discounts, 0.5);
  const Advantages b = compute_gae(r, v, 0.0, 0.9, 0.5);
  EXPECT_EQ(a.advantages, b.advantages);
  EXPECT_EQ(a.returns, b.returns);
}

}  // namespace
}  // namespace pnp::rl
