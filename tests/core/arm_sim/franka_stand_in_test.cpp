// The stand-in Franka as franka_ros would show it: its equilibrium and state in the end
// effector's frame, and the reflexes a Panda would take.

#include "arm_sim/franka_stand_in.h"

#include <gtest/gtest.h>

namespace pnp::arm_sim {
namespace {

geometry::Pose pose_of(const Eigen::Matrix4d& m) {
  return {m.topRightCorner<3, 1>(),
          Eigen::Quaterniond(Eigen::Matrix3d(m.topLeftCorner<3, 3>())).normalized()};
}

TEST(FrankaStandIn, AnEquilibriumAtTheEndEffectorHoldsAndAStepMovesTheGripPointByIt) {
  FrankaStandIn arm({});
  arm.reset(3);
  const FrankaStandInState start = arm.state();
  EXPECT_EQ(start.robot_mode, kFrankaModeMove);
  arm.set_equilibrium(pose_of(start.base_from_ee), std::chrono::system_clock::now());
  arm.advance(0.2);
  const Eigen::Vector3d grip0 = arm.arm().state().tcp_base.position_m;
  // O_T_EE is the grip point moved back along the flange and through F_T_EE.
  Eigen::Matrix4d flange_from_grip = Eigen::Matrix4d::Identity();
  flange_from_grip(2, 3) = 0.0934;
  const Eigen::Matrix4d grip =
      arm.state().base_from_ee * arm.state().flange_from_ee.inverse() * flange_from_grip;
  EXPECT_LT((grip.topRightCorner<3, 1>() - grip0).norm(), 1e-9);
  // 2 cm down in the end effector's pose is 2 cm down at the grip point.
  geometry::Pose lower = pose_of(start.base_from_ee);
  lower.position_m.z() -= 0.02;
  arm.set_equilibrium(lower, std::chrono::system_clock::now());
  arm.advance(0.5);
  const Eigen::Vector3d grip1 = arm.arm().state().tcp_base.position_m;
  EXPECT_NEAR(grip1.z() - grip0.z(), -0.02, 1e-3);
  EXPECT_NEAR((grip1 - grip0).head<2>().norm(), 0, 1e-3);
  EXPECT_TRUE(arm.state().current_errors.empty());
}

TEST(FrankaStandIn, AnEquilibriumFarFromTheHandIsACartesianReflexUntilRecovery) {
  FrankaStandIn arm({});
  arm.reset(3);
  geometry::Pose far = pose_of(arm.state().base_from_ee);
  far.position_m.x() += 0.3;
  arm.set_equilibrium(far, std::chrono::system_clock::now());
  arm.advance(0.01);
  EXPECT_EQ(arm.state().robot_mode, kFrankaModeReflex);
  EXPECT_EQ(arm.state().current_errors, std::vector<std::string>{"cartesian_reflex"});
  arm.set_equilibrium(pose_of(arm.state().base_from_ee),
                      std::chrono::system_clock::now());  // ignored in a reflex
  EXPECT_TRUE(arm.error_recovery());
  EXPECT_EQ(arm.state().robot_mode, kFrankaModeMove);
  EXPECT_FALSE(arm.error_recovery());  // nothing left to clear
}

TEST(FrankaStandIn, AnEquilibriumSentBeforeTheSceneWasResetIsIgnored) {
  FrankaStandIn arm({});
  const auto before = std::chrono::system_clock::now();
  arm.reset(3, before + std::chrono::milliseconds(1));
  geometry::Pose far = pose_of(arm.state().base_from_ee);
  far.position_m.x() += 0.3;  // where the hand was in the last scene
  arm.set_equilibrium(far, before);
  arm.advance(0.01);
  EXPECT_TRUE(arm.state().current_errors.empty());
}

}  // namespace
}  // namespace pnp::arm_sim
