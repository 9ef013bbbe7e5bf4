// Calibration from touched points: a known transform is recovered from noisy pairs, a bad
// point shows as its residual, and sets that leave the rotation free are refused by name.
#include "geometry/point_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "common/error.h"
#include "common/rng.h"

namespace pnp::geometry {
namespace {

// The simulation's table points, as a lab would touch them: a spread over the table.
const std::vector<Eigen::Vector3d> kTablePoints{{1.05, 0.45, 0.42}, {1.55, 0.45, 0.42},
                                                {1.55, 1.05, 0.42}, {1.05, 1.05, 0.42},
                                                {1.30, 0.75, 0.52}, {1.20, 0.60, 0.47}};

RigidTransform known() {
  return RigidTransform::from_translation_rpy({-0.88, -0.75, -0.40}, 0.02, -0.03,
                                              std::numbers::pi / 6, "known");
}

std::vector<PointPair> pairs_through(const RigidTransform& t, double noise_m, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<PointPair> pairs;
  for (const auto& p : kTablePoints) {
    const Eigen::Vector3d noise(rng.normal() * noise_m, rng.normal() * noise_m,
                                rng.normal() * noise_m);
    pairs.push_back({p, t.apply(p) + noise});
  }
  return pairs;
}

double angle_between(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

TEST(PointFit, RecoversAKnownTransformFromExactPairs) {
  const PointFit fit = fit_rigid_transform(pairs_through(known(), 0, 1), "pairs");
  EXPECT_LT(angle_between(fit.parent_from_child.rotation(), known().rotation()), 1e-9);
  EXPECT_LT((fit.parent_from_child.translation_m() - known().translation_m()).norm(), 1e-9);
  EXPECT_LT(fit.rms_m, 1e-9);
}

TEST(PointFit, RecoversAKnownTransformFromPairsWithAMillimetreOfNoise) {
  const PointFit fit = fit_rigid_transform(pairs_through(known(), 0.001, 7), "pairs");
  EXPECT_LT(angle_between(fit.parent_from_child.rotation(), known().rotation()),
            0.5 * std::numbers::pi / 180);
  // What matters is where the table's points land (the translation alone carries the
  // rotation's small error times the lever arm to the frame's origin, a metre away).
  for (const auto& p : kTablePoints)
    EXPECT_LT((fit.parent_from_child.apply(p) - known().apply(p)).norm(), 0.003);
  ASSERT_EQ(fit.residuals_m.size(), kTablePoints.size());
  for (const double r : fit.residuals_m) EXPECT_LT(r, 0.005);
}

TEST(PointFit, AMistouchedPointStandsOutByItsResidual) {
  auto pairs = pairs_through(known(), 0, 3);
  pairs[2].parent_m.z() += 0.03;  // the fingertips 3 cm above the table
  const PointFit fit = fit_rigid_transform(pairs, "pairs");
  const auto worst = std::max_element(fit.residuals_m.begin(), fit.residuals_m.end());
  EXPECT_EQ(worst - fit.residuals_m.begin(), 2);
}

TEST(PointFit, AMirroredSetGivesARotationNeverAReflection) {
  auto pairs = pairs_through(RigidTransform::identity(), 0, 5);
  for (auto& p : pairs) p.parent_m.x() = -p.parent_m.x();  // a sign typed wrong
  const PointFit fit = fit_rigid_transform(pairs, "pairs");
  EXPECT_NEAR(fit.parent_from_child.rotation().determinant(), 1.0, 1e-9);
  EXPECT_GT(fit.rms_m, 0.05) << "the mirror shows as residuals";
}

TEST(PointFit, SetsThatLeaveTheRotationFreeAreRefusedByName) {
  const auto refusal = [](std::vector<PointPair> pairs) {
    try {
      fit_rigid_transform(pairs, "pairs");
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  auto two = pairs_through(known(), 0, 1);
  two.resize(2);
  EXPECT_NE(refusal(two).find("at least 3 point pairs"), std::string::npos) << refusal(two);
  std::vector<PointPair> line;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p(1.0 + 0.1 * k, 0.5, 0.42);
    line.push_back({p, known().apply(p)});
  }
  EXPECT_NE(refusal(line).find("not on one line"), std::string::npos) << refusal(line);
  std::vector<PointPair> huddled;
  for (const auto& p : kTablePoints) {
    const Eigen::Vector3d q = Eigen::Vector3d(1.3, 0.75, 0.42) + 0.02 * (p - kTablePoints[4]);
    huddled.push_back({q, known().apply(q)});
  }
  EXPECT_NE(refusal(huddled).find("touch points across the table"), std::string::npos)
      << refusal(huddled);
  auto nan = pairs_through(known(), 0, 1);
  nan[1].parent_m.y() = std::nan("");
  EXPECT_NE(refusal(nan).find("pairs[1]"), std::string::npos) << refusal(nan);
}

}  // namespace
}  // namespace pnp::geometry
