// The motion generator's set point, sampled at 1 kHz as a controller streams it: it must
// reach the target, never pass it, and never ask more than the Panda's Cartesian limits.

#include "robot/cartesian_motion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"

namespace pnp::robot {
namespace {

constexpr double kDt = 0.001;

struct Extremes {
  double speed = 0, acceleration = 0, jerk = 0, angular_speed = 0;
  double overshoot_m = 0;  // past the target along the line from the start
  int ticks = 0;           // until the set point rests at the target
};

// Runs until at rest at the target (or `max_ticks`), differencing the set point.
Extremes run(CartesianMotion& motion, int max_ticks = 10000) {
  Extremes e;
  const Eigen::Vector3d start = motion.setpoint().position_m;
  const Eigen::Vector3d goal = motion.target().position_m;
  const Eigen::Vector3d direction = (goal - start).normalized();
  Eigen::Vector3d last_position = start;
  Eigen::Vector3d last_velocity = motion.velocity();  // a motion may be under way
  Eigen::Vector3d last_acceleration = motion.acceleration();
  Eigen::Quaterniond last_orientation = motion.setpoint().orientation;
  for (; e.ticks < max_ticks; ++e.ticks) {
    motion.advance(kDt);
    const Eigen::Vector3d v = (motion.setpoint().position_m - last_position) / kDt;
    const Eigen::Vector3d a = (v - last_velocity) / kDt;
    e.speed = std::max(e.speed, v.norm());
    e.acceleration = std::max(e.acceleration, a.norm());
    e.jerk = std::max(e.jerk, ((a - last_acceleration) / kDt).norm());
    e.angular_speed = std::max(
        e.angular_speed, last_orientation.angularDistance(motion.setpoint().orientation) / kDt);
    if (!(goal - start).isZero()) {
      e.overshoot_m = std::max(e.overshoot_m, (motion.setpoint().position_m - goal).dot(direction));
    }
    last_position = motion.setpoint().position_m;
    last_velocity = v;
    last_acceleration = a;
    last_orientation = motion.setpoint().orientation;
    if (motion.at_rest() && motion.setpoint().position_m == motion.target().position_m &&
        motion.setpoint().orientation.isApprox(motion.target().orientation, 0)) {
      break;
    }
  }
  return e;
}

const geometry::Pose kStart{Eigen::Vector3d(0.4, 0.0, 0.2), Eigen::Quaterniond::Identity()};

TEST(CartesianMotion, APolicyStepIsReachedWithinThePandasLimitsWithoutOvershoot) {
  const CartesianLimits limits;
  for (const double step_m : {0.001, 0.025, 0.05, 0.087}) {
    CartesianMotion motion(kStart, limits);
    motion.set_target({kStart.position_m + Eigen::Vector3d(step_m, -step_m, step_m) / std::sqrt(3),
                       kStart.orientation});
    const Extremes e = run(motion);
    SCOPED_TRACE(step_m);
    EXPECT_LT(e.ticks, 400);  // arrives: a 8.7 cm step in well under 0.4 s
    EXPECT_LE(e.speed, limits.speed_m_per_s * (1 + 1e-9));
    EXPECT_LE(e.acceleration, limits.acceleration_m_per_s2 * (1 + 1e-6));
    EXPECT_LE(e.jerk, limits.jerk_m_per_s3 * (1 + 1e-6));
    EXPECT_LE(e.overshoot_m, 1e-4);
  }
}

TEST(CartesianMotion, ALongMoveKeepsToTheRequestedSpeed) {
  CartesianMotion motion(kStart, {});
  motion.set_target({kStart.position_m + Eigen::Vector3d(0.0, 0.5, 0.0), kStart.orientation}, 0.25);
  const Extremes e = run(motion);
  EXPECT_NEAR(e.speed, 0.25, 1e-9);
  // Cruising most of the way; the last centimetres close exponentially (the position
  // loop's 40 ms time constant) to rest exactly on the target.
  EXPECT_GT(e.ticks * kDt, 0.5 / 0.25);
  EXPECT_LT(e.ticks * kDt, 0.5 / 0.25 + 0.3);
}

TEST(CartesianMotion, AStopBrakesWithinTheLimitsAndHoldsWhereItRests) {
  const CartesianLimits limits;
  CartesianMotion motion(kStart, limits);
  motion.set_target({kStart.position_m + Eigen::Vector3d(0.3, 0.0, 0.0), kStart.orientation});
  for (int k = 0; k < 150; ++k) motion.advance(kDt);
  const double speed = motion.velocity().norm();
  ASSERT_GT(speed, 0.5);
  motion.stop();
  const Extremes e = run(motion);
  EXPECT_TRUE(motion.at_rest());
  EXPECT_EQ(motion.target().position_m, motion.setpoint().position_m);
  EXPECT_LT(motion.setpoint().position_m.x(), kStart.position_m.x() + 0.3);  // short of it
  EXPECT_LE(e.acceleration, limits.acceleration_m_per_s2 * (1 + 1e-6));
  EXPECT_LE(e.jerk, limits.jerk_m_per_s3 * (1 + 1e-6));
  // Braking at the full limit, then the velocity loop's last few time constants.
  EXPECT_LT(e.ticks * kDt, speed / limits.acceleration_m_per_s2 + 0.1);
}

TEST(CartesianMotion, ATurnIsReachedWithinTheAngularSpeedLimit) {
  const CartesianLimits limits;
  CartesianMotion motion(kStart, limits);
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
  motion.set_target({kStart.position_m, turned});
  const Extremes e = run(motion);
  EXPECT_LT(e.ticks, 1000);
  EXPECT_LE(e.angular_speed, limits.angular_speed_rad_per_s * (1 + 1e-6));
  EXPECT_TRUE(motion.setpoint().orientation.isApprox(turned, 1e-12));
}

TEST(CartesianMotion, LimitsThatAreNotPositiveAreRefusedByName) {
  CartesianLimits limits;
  limits.jerk_m_per_s3 = 0;
  try {
    CartesianMotion motion(kStart, limits);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("jerk_m_per_s3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pnp::robot
