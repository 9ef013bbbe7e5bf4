// The franka_ros definitions in proto/ros must be franka_ros's on the wire: ROS 1 refuses a
// connection whose MD5 differs, so a field out of place would leave the bridge deaf to a
// real franka_control. Each value is what `rosmsg md5` prints for franka_ros 0.10.1; those
// of FrankaState, Errors, GraspActionGoal and MoveActionGoal are also the ones published
// in rosserial's generated franka headers.

#include <gtest/gtest.h>

#include <string>

#include "franka_gripper/GraspAction.h"
#include "franka_gripper/HomingAction.h"
#include "franka_gripper/MoveAction.h"
#include "franka_gripper/StopAction.h"
#include "franka_msgs/ErrorRecoveryAction.h"
#include "franka_msgs/FrankaState.h"
#include "services/franka_ros/franka_errors.h"

namespace {

template <typename Message>
std::string md5() {
  return ros::message_traits::MD5Sum<Message>::value();
}

template <typename Message>
std::string type() {
  return ros::message_traits::DataType<Message>::value();
}

TEST(FrankaMessages, StateAndErrorsAreFrankaRos) {
  EXPECT_EQ(type<franka_msgs::FrankaState>(), "franka_msgs/FrankaState");
  EXPECT_EQ(md5<franka_msgs::FrankaState>(), "431567d5df6caf4e4dd7385f25cb71ee");
  EXPECT_EQ(md5<franka_msgs::Errors>(), "082e9a670c96d8bc64b53e32777458e7");
}

TEST(FrankaMessages, ErrorRecoveryActionIsFrankaRos) {
  EXPECT_EQ(md5<franka_msgs::ErrorRecoveryAction>(), "d5a016b49f278075666fbc901debbd08");
  EXPECT_EQ(md5<franka_msgs::ErrorRecoveryActionGoal>(), "4b30be6cd12b9e72826df56b481f40e0");
  EXPECT_EQ(md5<franka_msgs::ErrorRecoveryActionResult>(), "1eb06eeff08fa7ea874431638cb52332");
  EXPECT_EQ(md5<franka_msgs::ErrorRecoveryActionFeedback>(), "aae20e09065c3809e8a8e87c4c8953fd");
}

TEST(FrankaMessages, GripperActionsAreFrankaRos) {
  EXPECT_EQ(md5<franka_gripper::GraspEpsilon>(), "95b2c5464a6f679bd1dacaf86414f095");
  EXPECT_EQ(md5<franka_gripper::GraspAction>(), "6f89449359949eaf1f0fef57b7e0db2a");
  EXPECT_EQ(md5<franka_gripper::GraspActionGoal>(), "7bd1a6e7f94ef15bb6dd05cb170e7909");
  EXPECT_EQ(md5<franka_gripper::GraspGoal>(), "627a0f0b10ad0c919fbd62b0b3427e63");
  EXPECT_EQ(md5<franka_gripper::GraspActionResult>(), "89dbc4e75593b525bbbea3a150532ed6");
  EXPECT_EQ(md5<franka_gripper::MoveAction>(), "85e8e11f508e446b706022926779afee");
  EXPECT_EQ(md5<franka_gripper::MoveActionGoal>(), "f8907a1e7bb902f2e4c7db8e1cf3d24f");
  EXPECT_EQ(md5<franka_gripper::MoveGoal>(), "d16050a0fe85f1c2cb8347c99678362e");
  EXPECT_EQ(md5<franka_gripper::HomingAction>(), "f37964fcdec026d9507d088d32b65b38");
  EXPECT_EQ(md5<franka_gripper::HomingActionGoal>(), "4b30be6cd12b9e72826df56b481f40e0");
  EXPECT_EQ(md5<franka_gripper::StopAction>(), "f37964fcdec026d9507d088d32b65b38");
  EXPECT_EQ(md5<franka_gripper::StopActionGoal>(), "4b30be6cd12b9e72826df56b481f40e0");
  EXPECT_EQ(md5<franka_gripper::MoveResult>(), "45872d25d65c97743cc71afc6d4e884d");
}

// The bridge reads the robot mode by these values; franka_ros numbers them so.
TEST(FrankaMessages, RobotModesKeepFrankaRosNumbers) {
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_OTHER, 0);
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_IDLE, 1);
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_MOVE, 2);
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_GUIDING, 3);
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_REFLEX, 4);
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_USER_STOPPED, 5);
  EXPECT_EQ(franka_msgs::FrankaState::ROBOT_MODE_AUTOMATIC_ERROR_RECOVERY, 6);
}

// The one table of error names has every flag of Errors, each under its own name.
TEST(FrankaMessages, EveryErrorFlagIsReadAndSetByItsName) {
  franka_msgs::Errors errors;
  EXPECT_TRUE(pnp::services::set_error_names(errors).empty());
  EXPECT_TRUE(pnp::services::set_error_flag(errors, "cartesian_reflex"));
  EXPECT_EQ(errors.cartesian_reflex, 1);
  EXPECT_EQ(pnp::services::set_error_names(errors), std::vector<std::string>{"cartesian_reflex"});
  EXPECT_FALSE(pnp::services::set_error_flag(errors, "not_an_error"));
  // Serialised, the message is 41 bytes: one per flag, so the table misses none.
  EXPECT_EQ(ros::serialization::serializationLength(errors), 41u);
  const std::vector<std::string> all = [] {
    std::vector<std::string> names;
    franka_msgs::Errors every;
    for (const char* name : {"joint_position_limits_violation", "base_acceleration_invalid_reading",
                             "tau_j_range_violation", "joint_reflex"}) {
      pnp::services::set_error_flag(every, name);
    }
    return pnp::services::set_error_names(every);
  }();
  EXPECT_EQ(all, (std::vector<std::string>{"joint_position_limits_violation", "joint_reflex",
                                           "tau_j_range_violation",
                                           "base_acceleration_invalid_reading"}));
}

}  // namespace
