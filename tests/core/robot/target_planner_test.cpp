#include "robot/target_planner.h"

#include <gtest/gtest.h>

#include <limits>

#include "common/error.h"
#include "sim/panda_hand.h"
#include "sim/world_layout.h"

namespace pnp::robot {
namespace {

const Eigen::Quaterniond kDown(0, 1, 0, 0);

// The deployed frame: panda_link0 at simulation (0.88, 0.75, 0.40), axes aligned.
GatewayConfig config() {
  GatewayConfig c;
  c.base_from_sim =
      geometry::RigidTransform::from_translation_rpy({-0.88, -0.75, -0.40}, 0, 0, 0, "test");
  return c;
}

// The arm holding a 5 cm block: the commanded point 1 cm below the measured one, as when
// the hand is pressed onto something (base frame).
ArmReading holding() {
  return {{{0.45, 0.0, 0.19}, kDown}, {{0.45, 0.0, 0.20}, kDown}, 0.05, kDown};
}

sim::Action action(double x, double y, double z, double grip) {
  sim::Action a;
  a << x, y, z, grip;
  return a;
}

const sim::WorldParameters& paper() {
  return sim::world_parameters(sim::WorldProfile::kPaper);
}
const sim::WorldParameters& gym() {
  return sim::world_parameters(sim::WorldProfile::kGym);
}

TEST(TargetPlanner, PaperWorldMovesTheCommandedPoint) {
  const PlannedTarget t = plan_target(config(), paper(), holding(), action(0.2, 0, 0.4, -0.5));
  EXPECT_TRUE(t.verdict.ok()) << t.verdict.reason;
  EXPECT_TRUE(t.base.pose.position_m.isApprox(Eigen::Vector3d(0.46, 0.0, 0.21), 1e-12))
      << t.base.pose.position_m.transpose();
  EXPECT_TRUE(t.sim.position_m.isApprox(Eigen::Vector3d(1.34, 0.75, 0.61), 1e-12));
  // Half the full 8 cm range, from the measured 5 cm.
  EXPECT_NEAR(t.base.gripper_width_m, 0.01, 1e-12);
}

TEST(TargetPlanner, GymWorldMovesTheMeasuredPoint) {
  const PlannedTarget t = plan_target(config(), gym(), holding(), action(0.2, 0, 0.4, -0.5));
  EXPECT_TRUE(t.verdict.ok()) << t.verdict.reason;
  EXPECT_TRUE(t.base.pose.position_m.isApprox(Eigen::Vector3d(0.46, 0.0, 0.22), 1e-12))
      << t.base.pose.position_m.transpose();
  // ctrl = q + a metres per finger: any sizeable action closes or opens fully.
  EXPECT_EQ(t.base.gripper_width_m, 0.0);
  EXPECT_EQ(plan_target(config(), gym(), holding(), action(0, 0, 0, 0.1)).base.gripper_width_m,
            0.08);
  EXPECT_NEAR(plan_target(config(), gym(), holding(), action(0, 0, 0, 0.005)).base.gripper_width_m,
              0.06, 1e-12);
}

TEST(TargetPlanner, OrientationIsTheEpisodesAndTheTargetStaysAboveTheFloor) {
  for (const auto* world : {&paper(), &gym()}) {
    ArmReading arm = holding();
    arm.commanded_base.position_m.z() = 0.014;  // just above the grip-point floor
    arm.measured_base.position_m.z() = 0.014;
    // The controller's commanded orientation has drifted by 0.05 rad: not copied back.
    arm.commanded_base.orientation =
        kDown * Eigen::Quaterniond(Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()));
    const PlannedTarget t = plan_target(config(), *world, arm, action(0, 0, -1, -1));
    EXPECT_TRUE(t.verdict.ok()) << t.verdict.reason;
    EXPECT_TRUE(t.clamped);
    EXPECT_NEAR(t.base.pose.position_m.z(), config().limits.workspace.min_m.z(), 1e-12);
    EXPECT_GE(t.base.pose.position_m.z(), sim::lowest_grip_point_z(0));
    EXPECT_TRUE(t.base.pose.orientation.isApprox(kDown));
    EXPECT_FALSE(plan_target(config(), *world, holding(), action(0, 0, 0.5, -1)).clamped);
  }
}

TEST(TargetPlanner, AStepPastTheSpeedLimitIsShortenedFromTheCommandedPose) {
  GatewayConfig c = config();
  c.limits.max_speed_m_per_s = 0.5;  // 2 cm per 40 ms period
  const PlannedTarget t = plan_target(c, paper(), holding(), action(1, 0, 0, -1));
  EXPECT_TRUE(t.rate_limited);
  EXPECT_TRUE(t.verdict.ok()) << t.verdict.reason;
  EXPECT_NEAR((t.base.pose.position_m - holding().commanded_base.position_m).norm(), 0.02, 1e-9);
}

TEST(TargetPlanner, APolicyNanIsRefusedAndABadReadingIsAnError) {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  for (const auto* world : {&paper(), &gym()}) {
    EXPECT_FALSE(plan_target(config(), *world, holding(), action(kNan, 0, 0, -1)).verdict.ok());
    EXPECT_FALSE(plan_target(config(), *world, holding(), action(0, 0, 0, kNan)).verdict.ok());
    ArmReading bad = holding();
    bad.measured_base.position_m.x() = kNan;
    EXPECT_THROW(plan_target(config(), *world, bad, action(0, 0, 0, -1)), Error);
    bad = holding();
    bad.gap_m = kNan;
    EXPECT_THROW(plan_target(config(), *world, bad, action(0, 0, 0, -1)), Error);
    bad = holding();
    bad.held_orientation_base = Eigen::Quaterniond(0, 0, 0, 0);
    EXPECT_THROW(plan_target(config(), *world, bad, action(0, 0, 0, -1)), Error);
  }
}

}  // namespace
}  // namespace pnp::robot
