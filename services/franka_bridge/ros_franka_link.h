#pragma once
// The bridge's ROS 1 side: franka_ros's topics and actions in and out, and nothing else
// (robot::FrankaBackend decides; this carries). Its source is built as C++17, because
// ROS 1's headers do not compile as C++20 (proto/ros/README.md): this header keeps ROS
// out of its interface.
//
// In: franka_msgs/FrankaState (franka_state_controller), sensor_msgs/JointState of the
// fingers (franka_gripper), geometry_msgs/PoseStamped of the object (a tracker).
// Out: geometry_msgs/PoseStamped equilibrium poses (franka_example_controllers'
// cartesian_impedance_example_controller), franka_gripper's move and grasp goals,
// franka_control's error_recovery goal.

#include <functional>
#include <memory>
#include <string>

#include "robot/franka_backend.h"
#include "services/franka_ros/franka_ros_names.h"

namespace pnp::services {

// Topic and action names, and frames; every one configurable (a lab's launch files
// differ). The defaults are franka_ros's own with franka_control.launch and
// cartesian_impedance_example_controller.launch.
struct FrankaTopics {
  std::string state = franka_ros_names::kState;
  std::string finger_joints = franka_ros_names::kFingerJoints;
  std::string equilibrium_pose = franka_ros_names::kEquilibriumPose;
  std::string object_pose = franka_ros_names::kObjectPose;
  std::string gripper = franka_ros_names::kGripper;  // its move and grasp actions
  std::string error_recovery = franka_ros_names::kErrorRecovery;
  // The frame every pose in and out is in: the arm's base.
  std::string base_frame = franka_ros_names::kBaseFrame;
  // The fingers' joint names in finger_joints; the width is their sum.
  std::string finger_joint_1 = "panda_finger_joint1";
  std::string finger_joint_2 = "panda_finger_joint2";
};

// What arrives, handed on from ROS's callback thread.
struct FrankaInputs {
  std::function<void(const robot::FrankaStateSample&)> on_state;
  std::function<void(double width_m)> on_gripper_width;
  std::function<void(const robot::TrackedObject&)> on_object;
  // A message that cannot be used (an object pose in another frame, say): why, once per
  // kind of problem and topic.
  std::function<void(const std::string& topic, const std::string& why)> on_refused;
};

class RosFrankaLink final : public robot::FrankaCommands {
 public:
  // Subscribes and advertises at once; callbacks arrive on a ROS spinner thread from then
  // on, until destruction.
  RosFrankaLink(const FrankaTopics& topics, FrankaInputs inputs);
  ~RosFrankaLink() override;
  RosFrankaLink(const RosFrankaLink&) = delete;
  RosFrankaLink& operator=(const RosFrankaLink&) = delete;

  void send_equilibrium_pose(const geometry::Pose& ee_base) override;
  void send_gripper_move(double width_m, double speed_m_per_s) override;
  void send_gripper_grasp(double width_m, double epsilon_inner_m, double epsilon_outer_m,
                          double speed_m_per_s, double force_n) override;
  void send_error_recovery() override;

  // How many subscribers the equilibrium topic has (franka_ros's controller, when up).
  int equilibrium_subscribers() const;
  // No callback runs after this returns (also on destruction): call it before what the
  // callbacks reach is destroyed.
  void stop_callbacks();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pnp::services
