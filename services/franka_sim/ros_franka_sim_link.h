#pragma once
// pnp-franka-sim's ROS 1 side: what franka_ros's nodes publish and serve, with the
// stand-in Franka behind it. Built as C++17 (proto/ros/README.md); ROS stays out of
// this header.
//
// Publishes franka_msgs/FrankaState (franka_state_controller), the arm's and the
// fingers' sensor_msgs/JointState, and (the stand-in's "tracker") the object's
// geometry_msgs/PoseStamped. Subscribes the impedance controller's equilibrium pose.
// Serves franka_gripper's move and grasp and franka_control's error_recovery actions.
// For tests only: std_msgs/String on <control>/inject_reflex puts the arm into a reflex
// with that error (one of franka_msgs/Errors' names; others are ignored), std_msgs/UInt64 on
// <control>/reset_scene starts that seed's episode, std_msgs/Float64 on
// <control>/stall_state or <control>/stall_tracker silences that topic for so many
// seconds (0 to kMaxStall_s; others are ignored) while the arm goes on.

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geometry/pose.h"
#include "services/franka_ros/franka_ros_names.h"

namespace pnp::services {

// The longest silence a test control may ask for.
inline constexpr double kMaxStall_s = 60;

struct FrankaSimTopics {
  std::string state = franka_ros_names::kState;
  std::string arm_joints = franka_ros_names::kArmJoints;
  std::string finger_joints = franka_ros_names::kFingerJoints;
  std::string equilibrium_pose = franka_ros_names::kEquilibriumPose;
  std::string object_pose = franka_ros_names::kObjectPose;
  std::string gripper = franka_ros_names::kGripper;
  std::string error_recovery = franka_ros_names::kErrorRecovery;
  std::string control = "/pnp_franka_sim";
  std::string base_frame = franka_ros_names::kBaseFrame;
};

// One state as FrankaState carries it (matrices column-major).
struct FrankaSimReport {
  double time_s = 0;
  std::array<double, 16> O_T_EE{}, O_T_EE_d{}, F_T_EE{};
  std::array<double, 7> q{}, dq{}, tau_J{};
  std::uint8_t robot_mode = 0;
  std::vector<std::string> current_errors;
  double finger_gap_m = 0;
  geometry::Pose object_base;
};

// What arrives, from ROS's threads; each returns whether the request succeeded.
struct FrankaSimInputs {
  std::function<void(const geometry::Pose& ee_base, std::chrono::system_clock::time_point stamp)>
      on_equilibrium;
  std::function<bool(double width_m)> on_move;
  std::function<bool(double width_m)> on_grasp;
  std::function<bool()> on_error_recovery;
  std::function<void(const std::string& error_name)> on_inject_reflex;
  std::function<void(std::uint64_t seed)> on_reset_scene;
  std::function<void(double seconds)> on_stall_state;
  std::function<void(double seconds)> on_stall_tracker;
};

class RosFrankaSimLink {
 public:
  RosFrankaSimLink(const FrankaSimTopics& topics, FrankaSimInputs inputs);
  ~RosFrankaSimLink();
  RosFrankaSimLink(const RosFrankaSimLink&) = delete;
  RosFrankaSimLink& operator=(const RosFrankaSimLink&) = delete;

  void publish_state(const FrankaSimReport& report);       // FrankaState and arm joints
  void publish_fingers(double finger_gap_m);               // the fingers' joint states
  void publish_object(const geometry::Pose& object_base);  // the tracker
  void stop_callbacks();  // none runs after this returns (also on destruction)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pnp::services
