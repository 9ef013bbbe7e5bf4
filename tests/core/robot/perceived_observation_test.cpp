#include "robot/perceived_observation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/error.h"

namespace pnp::robot {
namespace {

namespace obs = sim::obs;

PerceivedState state_at(double t) {
  PerceivedState s;
  s.gripper_m = Eigen::Vector3d(1.3, 0.75, 0.6) + t * Eigen::Vector3d(0.01, -0.02, 0.03);
  s.finger_gap_m = 0.06 - t * 0.01;
  s.object_m = Eigen::Vector3d(1.4, 0.8, 0.425) + t * Eigen::Vector3d(0.0, 0.01, 0.0);
  s.object_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * t, Eigen::Vector3d::UnitZ()));
  return s;
}

TEST(PerceivedObservation, PositionsAndZeroVelocitiesOnTheFirstUpdate) {
  PerceivedObservation p;
  const PerceivedState s = state_at(0);
  const sim::Observation o = p.update(s);
  EXPECT_EQ(sim::gripper_position(o), s.gripper_m);
  EXPECT_EQ(sim::object_position(o), s.object_m);
  EXPECT_TRUE(o.segment<3>(obs::kObjectRelPos).isApprox(s.object_m - s.gripper_m));
  EXPECT_DOUBLE_EQ(sim::finger_gap(o), 0.06);
  EXPECT_DOUBLE_EQ(o(obs::kFingerPos), 0.03);
  EXPECT_TRUE(o.segment<3>(obs::kObjectEuler).isZero(1e-12));
  EXPECT_TRUE(o.segment<11>(obs::kObjectRelVel).isZero(0));  // every velocity entry
}

TEST(PerceivedObservation, VelocitiesAreChangesSinceThePreviousUpdate) {
  PerceivedObservation p;
  p.update(state_at(0));
  const sim::Observation o = p.update(state_at(1));
  const Eigen::Vector3d gripper_change(0.01, -0.02, 0.03);
  const Eigen::Vector3d object_change(0.0, 0.01, 0.0);
  EXPECT_TRUE(o.segment<3>(obs::kGripperVel).isApprox(gripper_change, 1e-12));
  EXPECT_TRUE(o.segment<3>(obs::kObjectRelVel).isApprox(object_change - gripper_change, 1e-12));
  EXPECT_TRUE(o.segment<3>(obs::kObjectAngVel).isApprox(Eigen::Vector3d(0, 0, 0.1), 1e-12));
  EXPECT_NEAR(o(obs::kFingerVel), -0.005, 1e-15);
  EXPECT_NEAR(o(obs::kFingerVel + 1), -0.005, 1e-15);
  EXPECT_NEAR(o(obs::kObjectEuler + 2), 0.1, 1e-12);  // yaw
  // The next update differences against this one, not the first.
  const sim::Observation o2 = p.update(state_at(3));
  EXPECT_TRUE(o2.segment<3>(obs::kGripperVel).isApprox(2 * gripper_change, 1e-12));
}

TEST(PerceivedObservation, ResetClearsTheVelocities) {
  PerceivedObservation p;
  p.update(state_at(0));
  p.reset();
  const sim::Observation o = p.update(state_at(1));
  EXPECT_TRUE(o.segment<11>(obs::kObjectRelVel).isZero(0));
}

TEST(PerceivedObservation, RefusesNaNAndBadValues) {
  PerceivedObservation p;
  PerceivedState s = state_at(0);
  s.object_m.y() = std::numeric_limits<double>::quiet_NaN();
  try {
    p.update(s);
    FAIL() << "expected an INVALID_ARGUMENT";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "perceived state: expected finite values, got a NaN or infinite value");
  }
  s = state_at(0);
  s.finger_gap_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(p.update(s), Error);
  s = state_at(0);
  s.finger_gap_m = -0.03;
  EXPECT_THROW(p.update(s), Error);
  // Closed on nothing, the simulated fingers read millimetres past zero: kept as is.
  s.finger_gap_m = -0.012;
  EXPECT_DOUBLE_EQ(sim::finger_gap(p.update(s)), -0.012);
  p.reset();
  s = state_at(0);
  s.object_orientation = Eigen::Quaterniond(2, 0, 0, 0);
  EXPECT_THROW(p.update(s), Error);
  // A refused update leaves no previous state behind: the next one has zero velocities.
  const sim::Observation o = p.update(state_at(1));
  EXPECT_TRUE(o.segment<11>(obs::kObjectRelVel).isZero(0));
}

}  // namespace
}  // namespace pnp::robot
