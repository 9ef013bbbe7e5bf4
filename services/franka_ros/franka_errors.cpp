// Built as C++17 (ROS 1's headers): see franka_errors.h.
#include "services/franka_ros/franka_errors.h"

#include <array>
#include <cstdint>
#include <utility>

namespace pnp::services {
namespace {

using Errors = franka_msgs::Errors;
using Flag = std::pair<const char*, Errors::_joint_reflex_type Errors::*>;

// franka_ros 0.10.1's Errors.msg, in its order.
constexpr std::array<Flag, 41> kFlags{{
    {"joint_position_limits_violation", &Errors::joint_position_limits_violation},
    {"cartesian_position_limits_violation", &Errors::cartesian_position_limits_violation},
    {"self_collision_avoidance_violation", &Errors::self_collision_avoidance_violation},
    {"joint_velocity_violation", &Errors::joint_velocity_violation},
    {"cartesian_velocity_violation", &Errors::cartesian_velocity_violation},
    {"force_control_safety_violation", &Errors::force_control_safety_violation},
    {"joint_reflex", &Errors::joint_reflex},
    {"cartesian_reflex", &Errors::cartesian_reflex},
    {"max_goal_pose_deviation_violation", &Errors::max_goal_pose_deviation_violation},
    {"max_path_pose_deviation_violation", &Errors::max_path_pose_deviation_violation},
    {"cartesian_velocity_profile_safety_violation",
     &Errors::cartesian_velocity_profile_safety_violation},
    {"joint_position_motion_generator_start_pose_invalid",
     &Errors::joint_position_motion_generator_start_pose_invalid},
    {"joint_motion_generator_position_limits_violation",
     &Errors::joint_motion_generator_position_limits_violation},
    {"joint_motion_generator_velocity_limits_violation",
     &Errors::joint_motion_generator_velocity_limits_violation},
    {"joint_motion_generator_velocity_discontinuity",
     &Errors::joint_motion_generator_velocity_discontinuity},
    {"joint_motion_generator_acceleration_discontinuity",
     &Errors::joint_motion_generator_acceleration_discontinuity},
    {"cartesian_position_motion_generator_start_pose_invalid",
     &Errors::cartesian_position_motion_generator_start_pose_invalid},
    {"cartesian_motion_generator_elbow_limit_violation",
     &Errors::cartesian_motion_generator_elbow_limit_violation},
    {"cartesian_motion_generator_velocity_limits_violation",
     &Errors::cartesian_motion_generator_velocity_limits_violation},
    {"cartesian_motion_generator_velocity_discontinuity",
     &Errors::cartesian_motion_generator_velocity_discontinuity},
    {"cartesian_motion_generator_acceleration_discontinuity",
     &Errors::cartesian_motion_generator_acceleration_discontinuity},
    {"cartesian_motion_generator_elbow_sign_inconsistent",
     &Errors::cartesian_motion_generator_elbow_sign_inconsistent},
    {"cartesian_motion_generator_start_elbow_invalid",
     &Errors::cartesian_motion_generator_start_elbow_invalid},
    {"cartesian_motion_generator_joint_position_limits_violation",
     &Errors::cartesian_motion_generator_joint_position_limits_violation},
    {"cartesian_motion_generator_joint_velocity_limits_violation",
     &Errors::cartesian_motion_generator_joint_velocity_limits_violation},
    {"cartesian_motion_generator_joint_velocity_discontinuity",
     &Errors::cartesian_motion_generator_joint_velocity_discontinuity},
    {"cartesian_motion_generator_joint_acceleration_discontinuity",
     &Errors::cartesian_motion_generator_joint_acceleration_discontinuity},
    {"cartesian_position_motion_generator_invalid_frame",
     &Errors::cartesian_position_motion_generator_invalid_frame},
    {"force_controller_desired_force_tolerance_violation",
     &Errors::force_controller_desired_force_tolerance_violation},
    {"controller_torque_discontinuity", &Errors::controller_torque_discontinuity},
    {"start_elbow_sign_inconsistent", &Errors::start_elbow_sign_inconsistent},
    {"communication_constraints_violation", &Errors::communication_constraints_violation},
    {"power_limit_violation", &Errors::power_limit_violation},
    {"joint_p2p_insufficient_torque_for_planning",
     &Errors::joint_p2p_insufficient_torque_for_planning},
    {"tau_j_range_violation", &Errors::tau_j_range_violation},
    {"instability_detected", &Errors::instability_detected},
    {"joint_move_in_wrong_direction", &Errors::joint_move_in_wrong_direction},
    {"cartesian_spline_motion_generator_violation",
     &Errors::cartesian_spline_motion_generator_violation},
    {"joint_via_motion_generator_planning_joint_limit_violation",
     &Errors::joint_via_motion_generator_planning_joint_limit_violation},
    {"base_acceleration_initialization_timeout", &Errors::base_acceleration_initialization_timeout},
    {"base_acceleration_invalid_reading", &Errors::base_acceleration_invalid_reading},
}};

}  // namespace

std::vector<std::string> set_error_names(const franka_msgs::Errors& errors) {
  std::vector<std::string> names;
  for (const auto& [name, flag] : kFlags) {
    if (errors.*flag) names.emplace_back(name);
  }
  return names;
}

bool set_error_flag(franka_msgs::Errors& errors, const std::string& name) {
  for (const auto& [flag_name, flag] : kFlags) {
    if (name == flag_name) {
      errors.*flag = 1;
      return true;
    }
  }
  return false;
}

}  // namespace pnp::services
