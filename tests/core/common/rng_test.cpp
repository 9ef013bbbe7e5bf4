#include "common/rng.h"

#include <gtest/gtest.h>

#include <set>

namespace pnp {
namespace {

TEST(Rng, SameSeedSameStream) {
  Rng a(42), b(42);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.next_u64(), b.next_u64());
}

TEST(Rng, DifferentSeedsDiffer) {
  Rng a(1), b(2);
  EXPECT_NE(a.next_u64(), b.next_u64());
}

TEST(Rng, KnownFirstValueIsStableAcrossPlatforms) {
  // Pins the generator: a change here changes every seeded result in the project.
  Rng rng(0);
  EXPECT_EQ(rng.next_u64(), 0x99EC5F36CB75F2B4ULL);
}

TEST(Rng, UniformStaysInRangeWithTheRightMean) {
  Rng rng(7);
  double sum = 0;
  constexpr int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform(-0.15, 0.15);
    ASSERT_GE(u, -0.15);
    ASSERT_LT(u, 0.15);
    sum += u;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.002);
}

TEST(Rng, NormalHasUnitVariance) {
  Rng rng(9);
  double sum = 0, sq = 0;
  constexpr int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = rng.normal();
    sum += x;
    sq += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sq / n, 1.0, 0.02);
}

TEST(Rng, BelowCoversTheRangeOnly) {
  Rng rng(3);
  std::set<std::uint64_t> seen;
  for (int i = 0; i < 1000; ++i) {
    const auto v = rng.below(5);
    ASSERT_LT(v, 5u);
    seen.insert(v);
  }
  EXPECT_EQ(seen.size(), 5u);
}

TEST(DeriveSeed, IndependentOfCallOrderAndDistinct) {
  std::set<std::uint64_t> seeds;
  for (std::uint64_t i = 0; i < 1000; ++i) seeds.insert(derive_seed(5, i));
  EXPECT_EQ(seeds.size(), 1000u);
  EXPECT_EQ(derive_seed(5, 17), derive_seed(5, 17));
  EXPECT_NE(derive_seed(5, 17), derive_seed(6, 17));
}

}  // namespace
}  // namespace pnp
