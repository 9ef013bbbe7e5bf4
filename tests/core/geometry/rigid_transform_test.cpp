#include "geometry/rigid_transform.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "common/error.h"
#include "support/refusal.h"

namespace pnp::geometry {
namespace {

using pnp::testing::refusal;

// Entry by entry: Eigen's vectorised 4x4 reductions trip a GCC 12 false positive
// (-Wuninitialized inside its AVX-512 headers) under -march=native.
double max_abs_diff(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) {
  double worst = 0;
  for (Eigen::Index i = 0; i < 4; ++i) {
    for (Eigen::Index j = 0; j < 4; ++j) worst = std::max(worst, std::abs(a(i, j) - b(i, j)));
  }
  return worst;
}

RigidTransform general() {
  return RigidTransform::from_translation_rpy({0.3, -1.2, 0.7}, 0.4, -1.1, 2.5, "t");
}

Eigen::Matrix4d with_rotation(const Eigen::Matrix3d& r) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = r;
  m.topRightCorner<3, 1>() = Eigen::Vector3d(0.1, 0.2, 0.3);
  return m;
}

TEST(RigidTransform, IdentityLeavesPointsAndPoses) {
  const RigidTransform t = RigidTransform::identity();
  EXPECT_TRUE(t.matrix().isIdentity(0));
  EXPECT_EQ(t.apply(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(1, 2, 3));
  const Pose p{{1, 2, 3}, Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()))};
  const Pose q = t.apply(p);
  EXPECT_TRUE(q.position_m.isApprox(p.position_m));
  EXPECT_NEAR(rotation_angle_rad(q.orientation, p.orientation), 0, 1e-12);
}

TEST(RigidTransform, TimesInverseIsIdentity) {
  const RigidTransform t = general();
  EXPECT_TRUE((t * t.inverse()).matrix().isIdentity(1e-12));
  EXPECT_TRUE((t.inverse() * t).matrix().isIdentity(1e-12));
  EXPECT_LT(max_abs_diff(t.matrix().inverse(), t.inverse().matrix()), 1e-12);
}

TEST(RigidTransform, ComposeMatchesMatrixProductAndApplyOrder) {
  const RigidTransform a = general();
  const RigidTransform b =
      RigidTransform::from_translation_rpy({-0.5, 0.25, 1.0}, -0.3, 0.2, 0.9, "b");
  EXPECT_LT(max_abs_diff((a * b).matrix(), a.matrix() * b.matrix()), 1e-12);
  const Eigen::Vector3d p(0.7, -0.1, 0.4);
  EXPECT_TRUE((a * b).apply(p).isApprox(a.apply(b.apply(p)), 1e-12));
}

TEST(RigidTransform, ApplyThenInverseApplyReturnsPointAndPose) {
  const RigidTransform t = general();
  const Eigen::Vector3d p(0.7, -0.1, 0.4);
  EXPECT_TRUE(t.inverse().apply(t.apply(p)).isApprox(p, 1e-12));
  const Pose pose{
      p, Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d(1, 2, 3).normalized()))};
  const Pose back = t.inverse().apply(t.apply(pose));
  EXPECT_TRUE(back.position_m.isApprox(pose.position_m, 1e-12));
  EXPECT_NEAR(rotation_angle_rad(back.orientation, pose.orientation), 0, 1e-9);
  EXPECT_NEAR(back.orientation.norm(), 1, 1e-12);
}

TEST(RigidTransform, ApplyPoseComposesRotationAndNormalises) {
  const RigidTransform yaw90 =
      RigidTransform::from_translation_rpy({1, 0, 0}, 0, 0, M_PI / 2, "yaw90");
  // A slightly unnormalised input still comes out unit.
  const Pose pose{{1, 0, 0}, Eigen::Quaterniond(1.0005, 0, 0, 0)};
  const Pose out = yaw90.apply(pose);
  EXPECT_TRUE(out.position_m.isApprox(Eigen::Vector3d(1, 1, 0), 1e-12));
  EXPECT_NEAR(out.orientation.norm(), 1, 1e-15);
  EXPECT_TRUE(out.orientation.toRotationMatrix().isApprox(yaw90.rotation(), 1e-12));
  EXPECT_TRUE(yaw90.rotate(Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
}

TEST(RigidTransform, JsonRoundTrip) {
  const RigidTransform t = general();
  const nlohmann::json j = t.to_json();
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 4u);
  EXPECT_EQ(j[3], nlohmann::json::array({0.0, 0.0, 0.0, 1.0}));
  EXPECT_LT(max_abs_diff(RigidTransform::from_json(j, "t").matrix(), t.matrix()), 1e-12);
  // Through text too, and a pure translation comes back exactly.
  const nlohmann::json translation =
      nlohmann::json::parse("[[1, 0, 0, -0.88], [0, 1, 0, -0.75], [0, 0, 1, -0.40], [0, 0, 0, 1]]");
  const RigidTransform u = RigidTransform::from_json(translation, "base_from_sim");
  EXPECT_EQ(u.translation_m(), Eigen::Vector3d(-0.88, -0.75, -0.40));
  EXPECT_TRUE(u.rotation().isIdentity(0));
  EXPECT_EQ(nlohmann::json::parse(u.to_json().dump()), translation);
}

TEST(RigidTransform, NearlyOrthonormalIsAcceptedAndMadeExact) {
  Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  r(0, 1) += 2e-7;  // a rotation written with 6 or 7 digits
  const RigidTransform t = RigidTransform::from_matrix(with_rotation(r), "t");
  EXPECT_TRUE((t.rotation().transpose() * t.rotation()).isIdentity(1e-14));
  EXPECT_NEAR(t.rotation().determinant(), 1, 1e-14);
  EXPECT_TRUE(t.rotation().isApprox(r, 1e-6));
}

TEST(RigidTransform, RefusesReflection) {
  const Eigen::Matrix3d mirror = Eigen::Vector3d(1, 1, -1).asDiagonal();
  EXPECT_EQ(refusal([&] { RigidTransform::from_matrix(with_rotation(mirror), "transform"); }),
            "transform: rotation part has det = -1, expected +1 (a reflection is not a rotation)");
}

TEST(RigidTransform, RefusesScaledRotation) {
  const Eigen::Matrix3d scaled = 1.1 * Eigen::Matrix3d::Identity();
  EXPECT_EQ(refusal([&] { RigidTransform::from_matrix(with_rotation(scaled), "transform"); }),
            "transform: rotation part is not orthonormal (max |R^T R - I| = 0.21, expected <= "
            "1e-06): a scale or shear is not a rigid transform");
}

TEST(RigidTransform, RefusesShear) {
  Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
  shear(0, 1) = 0.2;
  EXPECT_EQ(refusal([&] { RigidTransform::from_matrix(with_rotation(shear), "base_from_sim"); }),
            "base_from_sim: rotation part is not orthonormal (max |R^T R - I| = 0.2, expected <= "
            "1e-06): a scale or shear is not a rigid transform");
}

TEST(RigidTransform, RefusesBadBottomRow) {
  Eigen::Matrix4d m = with_rotation(Eigen::Matrix3d::Identity());
  m(3, 2) = 1;
  EXPECT_EQ(refusal([&] { RigidTransform::from_matrix(m, "transform"); }),
            "transform: bottom row is (0, 0, 1, 1), expected (0, 0, 0, 1) within 1e-09");
  m(3, 2) = 0;
  m(3, 3) = 2;  // a projective scale
  EXPECT_EQ(refusal([&] { RigidTransform::from_matrix(m, "transform"); }),
            "transform: bottom row is (0, 0, 0, 2), expected (0, 0, 0, 1) within 1e-09");
}

TEST(RigidTransform, RefusesNonFinite) {
  Eigen::Matrix4d m = with_rotation(Eigen::Matrix3d::Identity());
  m(1, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(refusal([&] { RigidTransform::from_matrix(m, "transform"); }),
            "transform[1][3]: expected a finite number, got nan");
  nlohmann::json j = RigidTransform::identity().to_json();
  j[0][0] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refusal([&] { RigidTransform::from_json(j, "transform"); }),
            "transform[0][0]: expected a finite number, got inf");
  EXPECT_EQ(refusal([] {
              RigidTransform::from_translation_rpy({0, 0, 0}, std::nan(""), 0, 0, "mount");
            }),
            "mount: expected a finite translation and finite roll, pitch, yaw, got translation "
            "(0, 0, 0), rpy (nan, 0, 0)");
}

TEST(RigidTransform, RefusesWrongJsonShape) {
  const std::string shape = "expected a row-major 4x4 matrix (an array of 4 arrays of 4 numbers)";
  EXPECT_EQ(refusal([] { RigidTransform::from_json(nlohmann::json::object(), "transform"); }),
            "transform: " + shape + ", got an object");
  EXPECT_EQ(refusal([] { RigidTransform::from_json(nlohmann::json(1.0), "transform"); }),
            "transform: " + shape + ", got 1.0");
  nlohmann::json j = RigidTransform::identity().to_json();
  j.erase(3);
  EXPECT_EQ(refusal([&] { RigidTransform::from_json(j, "transform"); }),
            "transform: " + shape + ", got an array of 3 rows");
  j = RigidTransform::identity().to_json();
  j[2].push_back(0.0);
  EXPECT_EQ(refusal([&] { RigidTransform::from_json(j, "transform"); }),
            "transform[2]: expected an array of 4 numbers, got 5 values");
  j = RigidTransform::identity().to_json();
  j[1] = "row";
  EXPECT_EQ(refusal([&] { RigidTransform::from_json(j, "transform"); }),
            "transform[1]: expected an array of 4 numbers, got a string");
  j = RigidTransform::identity().to_json();
  j[2][3] = "0.5";
  EXPECT_EQ(refusal([&] { RigidTransform::from_json(j, "transform"); }),
            "transform[2][3]: expected a number, got \"0.5\"");
}

}  // namespace
}  // namespace pnp::geometry
