#include "robot/safety_limits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "common/error.h"
#include "robot/rate_limit.h"
#include "sim/panda_hand.h"
#include "sim/world_layout.h"
#include "support/refusal.h"

namespace pnp::robot {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kPeriod = 0.04;

using pnp::testing::refusal;

// Pointing down, as the policy's gripper does.
const Eigen::Quaterniond kDown(0, 1, 0, 0);

geometry::Pose previous() {
  return {{0.45, 0.0, 0.2}, kDown};
}

PoseTarget target_at(const Eigen::Vector3d& p) {
  return {{p, kDown}, 0.04};
}

SafetyVerdict check(const PoseTarget& t) {
  return check_target(SafetyLimits{}, t, previous(), kPeriod);
}

void expect_refused(const PoseTarget& t, SafetyRefusal why, const std::string& reason) {
  const SafetyVerdict v = check(t);
  EXPECT_FALSE(v.ok());
  ASSERT_TRUE(v.refusal.has_value());
  EXPECT_EQ(safety_refusal_name(*v.refusal), safety_refusal_name(why));
  EXPECT_EQ(v.reason, reason);
}

TEST(SafetyLimits, DefaultsAreValidAndCoverTheSimulatedTaskBox) {
  const SafetyLimits limits;
  EXPECT_NO_THROW(limits.validate());
  // The simulated Panda's panda_link0 sits at world (0.88, 0.75, 0.40), axes aligned.
  const Eigen::Vector3d base(0.88, 0.75, 0.40);
  Eigen::Vector3d lo = sim::layout::kWorkspaceMin - base;
  const Eigen::Vector3d hi = sim::layout::kWorkspaceMax - base;
  // ... except its floor (5 mm above the table, where the pads would be in it), raised
  // to the lowest grip point that keeps the pads clear.
  EXPECT_LT(lo.z(), sim::lowest_grip_point_z(0));
  lo.z() = limits.workspace.min_m.z();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                            (corner & 4) ? hi.z() : lo.z());
    EXPECT_TRUE(limits.workspace.contains(p)) << p.transpose();
  }
  EXPECT_TRUE(limits.workspace.contains(sim::layout::kGripperStart - base));
  // ... with the margin in x, y and up; the floor within a millimetre of the lowest.
  EXPECT_GE(limits.workspace.min_m.z(), sim::lowest_grip_point_z(limits.table_top_z_m));
  EXPECT_LT(limits.workspace.min_m.z(), sim::lowest_grip_point_z(limits.table_top_z_m) + 1e-3);
  EXPECT_NEAR((lo - limits.workspace.min_m).head<2>().minCoeff(), 0.03, 1e-12);
  EXPECT_NEAR((limits.workspace.max_m - hi).minCoeff(), 0.03, 1e-12);
  // A full policy action (0.05 m on each axis) is neither a too large step nor too fast
  // once clipped to the speed limit.
  EXPECT_LE(std::sqrt(3.0) * sim::layout::kActionPositionScale, limits.max_step_m);
}

TEST(SafetyLimits, AFloorThatLetsThePadsIntoTheTableOrAnImplausibleBoxIsRefused) {
  SafetyLimits l;
  l.workspace.min_m.z() = 0.005;  // the floor before: the pads 5 mm into the table
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.workspace.min_m[2]: expected at least 0.0121 m: the table top (0 m) + the "
            "pads' reach below the grip point (0.0101 m) + 0.002 m clearance, got 0.005");
  l = SafetyLimits{};
  l.table_top_z_m = 0.05;  // the table moved up: the same floor is now inside it
  EXPECT_NE(refusal([&] { l.validate(); }).find("limits.workspace.min_m[2]"), std::string::npos);
  l = SafetyLimits{};
  l.workspace.max_m.x() = 7.0;  // a typo for 0.7
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.workspace.max_m[0]: expected within the Panda's reach, |x| <= 0.855 m, got 7");
  l = SafetyLimits{};
  l.workspace.max_m.z() = 4.8;
  EXPECT_NE(refusal([&] { l.validate(); }).find("limits.workspace.max_m[2]: expected at most"),
            std::string::npos);
  l = SafetyLimits{};
  l.table_top_z_m = std::nan("");
  EXPECT_NE(refusal([&] { l.validate(); }).find("limits.table_top_z_m"), std::string::npos);
}

TEST(SafetyLimits, ValidateNamesTheField) {
  SafetyLimits l;
  l.workspace.min_m.y() = 0.5;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.workspace.min_m[1]: expected less than limits.workspace.max_m[1] (0.38 m, the "
            "y axis), got 0.5");
  l = SafetyLimits{};
  l.workspace.max_m.z() = kNan;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.workspace.max_m[2]: expected a finite number, got nan");
  l = SafetyLimits{};
  l.max_step_m = 0;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.max_step_m: expected a positive finite number (m), got 0");
  l = SafetyLimits{};
  l.max_speed_m_per_s = -1.7;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.max_speed_m_per_s: expected a positive finite number (m/s), got -1.7");
  l = SafetyLimits{};
  l.max_rotation_step_rad = kNan;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.max_rotation_step_rad: expected a positive finite number (rad), got nan");
  l = SafetyLimits{};
  l.gripper_min_width_m = -0.01;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.gripper_min_width_m: expected a finite width >= 0 m, got -0.01");
  l = SafetyLimits{};
  l.gripper_max_width_m = 0;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.gripper_max_width_m: expected a finite width greater than "
            "limits.gripper_min_width_m (0 m), got 0");
  l = SafetyLimits{};
  l.quaternion_norm_tolerance = 1;
  EXPECT_EQ(refusal([&] { l.validate(); }),
            "limits.quaternion_norm_tolerance: expected a number in (0, 1), got 1");
}

TEST(SafetyLimits, AcceptsAPolicyStep) {
  PoseTarget t = target_at(previous().position_m + Eigen::Vector3d(0.03, -0.03, 0.03));
  const SafetyVerdict v = check(t);
  EXPECT_TRUE(v.ok()) << v.reason;
  EXPECT_EQ(v.reason, "");
  // The same orientation written as -q, a small turn, and the gripper's ends are fine.
  t.pose.orientation = Eigen::Quaterniond(-kDown.coeffs());
  EXPECT_TRUE(check(t).ok());
  t.pose.orientation =
      kDown * Eigen::Quaterniond(Eigen::AngleAxisd(0.19, Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(check(t).ok());
  t.gripper_width_m = 0;
  EXPECT_TRUE(check(t).ok());
  t.gripper_width_m = 0.08;
  EXPECT_TRUE(check(t).ok());
}

TEST(SafetyLimits, RefusesNonFinitePosition) {
  expect_refused(target_at({0.45, kNan, 0.2}), SafetyRefusal::kNonFinite,
                 "target position (0.45, nan, 0.2) m is not finite");
}

TEST(SafetyLimits, RefusesNonFiniteOrientation) {
  PoseTarget t = target_at(previous().position_m);
  t.pose.orientation.w() = std::numeric_limits<double>::infinity();
  expect_refused(t, SafetyRefusal::kNonFinite,
                 "target orientation (w inf, x 1, y 0, z 0) is not finite");
}

TEST(SafetyLimits, RefusesNonFiniteGripper) {
  PoseTarget t = target_at(previous().position_m);
  t.gripper_width_m = kNan;
  expect_refused(t, SafetyRefusal::kNonFinite, "target gripper width nan m is not finite");
}

TEST(SafetyLimits, RefusesNonUnitQuaternion) {
  PoseTarget t = target_at(previous().position_m);
  t.pose.orientation = Eigen::Quaterniond(0, 1.01, 0, 0);
  expect_refused(t, SafetyRefusal::kBadQuaternion,
                 "target orientation quaternion has norm 1.01, expected 1 within 0.001");
  t.pose.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  expect_refused(t, SafetyRefusal::kBadQuaternion,
                 "target orientation quaternion has norm 0, expected 1 within 0.001");
}

TEST(SafetyLimits, RefusesOutsideTheBoxOnEachAxis) {
  // The previous command sits next to the crossed face, so only the box refuses.
  const SafetyLimits limits;
  const WorkspaceBox& box = limits.workspace;
  struct Case {
    Eigen::Vector3d p;
    std::string reason;
  };
  const Case cases[] = {
      {{0.71, 0.0, 0.2}, "position (0.71, 0, 0.2) m outside workspace x [0.14, 0.7] m"},
      {{0.13, 0.0, 0.2}, "position (0.13, 0, 0.2) m outside workspace x [0.14, 0.7] m"},
      {{0.45, 0.39, 0.2}, "position (0.45, 0.39, 0.2) m outside workspace y [-0.38, 0.38] m"},
      {{0.45, -0.39, 0.2}, "position (0.45, -0.39, 0.2) m outside workspace y [-0.38, 0.38] m"},
      {{0.45, 0.0, 0.49}, "position (0.45, 0, 0.49) m outside workspace z [0.013, 0.48] m"},
      {{0.45, 0.0, 0.0}, "position (0.45, 0, 0) m outside workspace z [0.013, 0.48] m"},
  };
  for (const Case& c : cases) {
    const geometry::Pose near{c.p.cwiseMax(box.min_m).cwiseMin(box.max_m), kDown};
    const SafetyVerdict v = check_target(limits, target_at(c.p), near, kPeriod);
    ASSERT_TRUE(v.refusal.has_value()) << c.reason;
    EXPECT_EQ(*v.refusal, SafetyRefusal::kOutsideWorkspace);
    EXPECT_EQ(v.reason, c.reason);
  }
}

TEST(SafetyLimits, RefusesTooLargeAStep) {
  expect_refused(target_at(previous().position_m + Eigen::Vector3d(0.12, 0, 0)),
                 SafetyRefusal::kStepTooLarge,
                 "step of 0.12 m from the previous command exceeds max_step_m 0.1 m");
}

TEST(SafetyLimits, RefusesTooFast) {
  // 0.08 m is within the step limit but is 2 m/s at 25 Hz.
  expect_refused(target_at(previous().position_m + Eigen::Vector3d(0, 0.08, 0)),
                 SafetyRefusal::kTooFast,
                 "speed 2 m/s (0.08 m in 0.04 s) exceeds max_speed_m_per_s 1.7 m/s");
  // The same step over a longer period is slow enough.
  const PoseTarget t = target_at(previous().position_m + Eigen::Vector3d(0, 0.08, 0));
  EXPECT_TRUE(check_target(SafetyLimits{}, t, previous(), 0.05).ok());
}

TEST(SafetyLimits, RefusesTooLargeARotationStep) {
  PoseTarget t = target_at(previous().position_m);
  t.pose.orientation = kDown * Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  expect_refused(t, SafetyRefusal::kRotationStepTooLarge,
                 "rotation of 0.3 rad from the previous command exceeds max_rotation_step_rad "
                 "0.2 rad");
}

TEST(SafetyLimits, RefusesGripperOutOfRange) {
  PoseTarget t = target_at(previous().position_m);
  t.gripper_width_m = 0.09;
  expect_refused(t, SafetyRefusal::kGripperOutOfRange, "gripper width 0.09 m outside [0, 0.08] m");
  t.gripper_width_m = -0.001;
  expect_refused(t, SafetyRefusal::kGripperOutOfRange,
                 "gripper width -0.001 m outside [0, 0.08] m");
}

TEST(SafetyLimits, ChecksInOrder) {
  // Outside the box, too far and with a bad gripper: the box is reported.
  PoseTarget t = target_at({2.0, 0.0, 0.2});
  t.gripper_width_m = 1;
  EXPECT_EQ(check(t).refusal, SafetyRefusal::kOutsideWorkspace);
  // A bad quaternion comes before the box.
  t.pose.orientation = Eigen::Quaterniond(2, 0, 0, 0);
  EXPECT_EQ(check(t).refusal, SafetyRefusal::kBadQuaternion);
}

TEST(SafetyLimits, RefusalNames) {
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kNonFinite), "non_finite");
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kBadQuaternion), "bad_quaternion");
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kOutsideWorkspace), "outside_workspace");
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kStepTooLarge), "step_too_large");
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kTooFast), "too_fast");
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kRotationStepTooLarge), "rotation_step_too_large");
  EXPECT_EQ(safety_refusal_name(SafetyRefusal::kGripperOutOfRange), "gripper_out_of_range");
}

TEST(SafetyLimits, CallerErrorsThrowInsteadOfRefusing) {
  const PoseTarget t = target_at(previous().position_m);
  EXPECT_EQ(refusal([&] { check_target(SafetyLimits{}, t, previous(), 0); }),
            "period_s: expected a positive finite duration (s), got 0");
  geometry::Pose bad = previous();
  bad.position_m.x() = kNan;
  EXPECT_EQ(refusal([&] { check_target(SafetyLimits{}, t, bad, kPeriod); }),
            "previous_commanded: expected a finite pose with a unit quaternion, got position "
            "(nan, 0, 0.2) m, orientation (w 0, x 1, y 0, z 0)");
  bad = previous();
  bad.orientation = Eigen::Quaterniond(0, 0, 0, 0);  // would make every rotation step NaN
  EXPECT_NE(refusal([&] { check_target(SafetyLimits{}, t, bad, kPeriod); }), "");
  SafetyLimits l;
  l.max_step_m = -1;
  EXPECT_EQ(refusal([&] { check_target(l, t, previous(), kPeriod); }),
            "limits.max_step_m: expected a positive finite number (m), got -1");
}

TEST(RateLimit, ClipsTranslationAndKeepsTheTargetOrientation) {
  const geometry::Pose from = previous();
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()));
  const geometry::Pose to{from.position_m + Eigen::Vector3d(0.3, 0.4, 0), turned};
  const geometry::Pose out = limit_step(from, to, 0.05);
  EXPECT_NEAR((out.position_m - from.position_m).norm(), 0.05, 1e-12);
  EXPECT_TRUE(
      (out.position_m - from.position_m).normalized().isApprox(Eigen::Vector3d(0.6, 0.8, 0)));
  EXPECT_TRUE(out.orientation.coeffs().isApprox(turned.coeffs()));
  // Within reach: unchanged.
  const geometry::Pose close{from.position_m + Eigen::Vector3d(0.01, 0, 0), turned};
  EXPECT_EQ(limit_step(from, close, 0.05).position_m, close.position_m);
}

TEST(RateLimit, ClippedToTheLimitPassesTheCheckAgainstIt) {
  const SafetyLimits limits;
  const geometry::Pose from = previous();
  for (const double distance : {limits.max_step_m, limits.max_speed_m_per_s * kPeriod}) {
    for (const Eigen::Vector3d& dir :
         {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(-0.3, 0.7, 0.1), Eigen::Vector3d(0, -1, 0)}) {
      const geometry::Pose to{from.position_m + dir, kDown};
      const PoseTarget t{limit_step(from, to, distance), 0.04};
      const SafetyVerdict v = check_target(limits, t, from, kPeriod);
      if (distance <= limits.max_speed_m_per_s * kPeriod) {
        EXPECT_TRUE(v.ok()) << v.reason;
      } else {
        EXPECT_EQ(v.refusal, SafetyRefusal::kTooFast);
      }
    }
  }
}

TEST(RateLimit, RefusesBadInput) {
  EXPECT_EQ(refusal([] { limit_step(previous(), previous(), 0); }),
            "max_distance_m: expected a positive finite distance (m), got 0");
  geometry::Pose bad = previous();
  bad.position_m.z() = kNan;
  EXPECT_EQ(refusal([&] { limit_step(previous(), bad, 0.1); }),
            "to: expected a finite pose, got a NaN or inf");
}

}  // namespace
}  // namespace pnp::robot
