#pragma once
// franka_ros's own topic and action names (franka_control.launch with
// cartesian_impedance_example_controller.launch) and the tracker topic the project
// expects: the defaults of pnp-franka-bridge and of its stand-in pnp-franka-sim, which must
// agree. Every one is a flag on both.

namespace pnp::services::franka_ros_names {

inline constexpr const char* kState = "/franka_state_controller/franka_states";
inline constexpr const char* kArmJoints = "/franka_state_controller/joint_states";
inline constexpr const char* kFingerJoints = "/franka_gripper/joint_states";
inline constexpr const char* kEquilibriumPose =
    "/cartesian_impedance_example_controller/equilibrium_pose";
inline constexpr const char* kObjectPose = "/pnp/object_pose";
inline constexpr const char* kGripper = "/franka_gripper";  // its move and grasp actions
inline constexpr const char* kErrorRecovery = "/franka_control/error_recovery";
inline constexpr const char* kBaseFrame = "panda_link0";

}  // namespace pnp::services::franka_ros_names
