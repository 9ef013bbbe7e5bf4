#include "common/validate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/error.h"
#include "support/refusal.h"

namespace pnp {
namespace {

using pnp::testing::refusal;

TEST(Validate, WrongSizeNamesFieldAndSizes) {
  const std::vector<double> v{1, 2, 3};
  EXPECT_EQ(refusal([&] { require_finite_vector(v, 4, "action"); }),
            "action: expected 4 values, got 3");
}

TEST(Validate, NonFiniteNamesTheIndex) {
  const std::vector<double> v{0, std::nan(""), 0};
  EXPECT_EQ(refusal([&] { require_finite_vector(v, 3, "goal"); }),
            "goal[1]: expected a finite number, got nan");
  const std::vector<double> w{std::numeric_limits<double>::infinity()};
  EXPECT_EQ(refusal([&] { require_finite(w, "x"); }), "x[0]: expected a finite number, got inf");
}

TEST(Validate, Positive) {
  EXPECT_NO_THROW(require_positive(1, "n"));
  EXPECT_EQ(refusal([] { require_positive(0, "num_envs"); }),
            "num_envs: expected a positive integer, got 0");
}

}  // namespace
}  // namespace pnp
