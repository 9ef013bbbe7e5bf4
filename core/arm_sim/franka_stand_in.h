#pragma once
// What pnp-franka-sim runs: the simulated Panda (SimulatedArm) behaving as franka_ros's
// franka_control with the Cartesian impedance controller and franka_gripper would, so
// the bridge's whole chain runs without an arm. It follows equilibrium poses of the end
// effector (the configured F_T_EE, by default a Franka Hand's: 0.1034 m down the flange,
// turned -45 degrees), reports the state FrankaState carries, moves and grasps with the
// hand, and goes into a reflex where a Panda would, until error recovery:
//   - cartesian_motion_generator_joint_position_limits_violation: an equilibrium the arm
//     cannot reach within its joint limits;
//   - cartesian_reflex: an equilibrium further than reflex_deviation_m from the end
//     effector (the stand-in's own rule: below);
//   - instability_detected: the physics failed;
//   - any error a test injects (inject_reflex).
// Its joint torques are those of the simulated arm's own tracking loop (clamped to the
// Panda's limits), not of franka_ros's impedance controller, so they raise no reflex.
// Not thread-safe: one owner calls everything (pnp-franka-sim under its own lock).

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "arm_sim/simulated_arm.h"
#include "geometry/rigid_transform.h"

namespace pnp::arm_sim {

// franka_msgs/FrankaState's robot modes used here.
inline constexpr std::uint8_t kFrankaModeMove = 2;
inline constexpr std::uint8_t kFrankaModeReflex = 4;

struct FrankaStandInOptions {
  sim::ObjectShape object = sim::ObjectShape::kBlock;
  sim::WorldProfile world = sim::kDefaultWorldProfile;
  ArmControllerOptions arm = [] {
    ArmControllerOptions o;
    o.policy_period_s = 0.001;  // an equilibrium every tick is followed within the tick
    return o;
  }();
  // The stand-in's own rule, not franka_ros's (whose impedance spring at its default
  // stiffness pulls with some tens of newtons there): a controller this far from the arm
  // has lost track of it. Wider than a policy step (8.7 cm) plus the arm's lag behind the
  // Cartesian set point, which reached 10 cm in gateway episodes.
  double reflex_deviation_m = 0.2;
  // Flange to end effector, what franka_control was configured with (FrankaState.F_T_EE).
  geometry::RigidTransform flange_from_ee = default_flange_from_ee();
  static geometry::RigidTransform default_flange_from_ee();
};

struct FrankaStandInState {
  double time_s = 0;
  Eigen::Matrix4d base_from_ee = Eigen::Matrix4d::Identity();          // O_T_EE
  Eigen::Matrix4d base_from_ee_desired = Eigen::Matrix4d::Identity();  // O_T_EE_d
  Eigen::Matrix4d flange_from_ee = Eigen::Matrix4d::Identity();        // F_T_EE
  JointVector q{}, dq{}, tau{};
  std::uint8_t robot_mode = kFrankaModeMove;
  std::vector<std::string> current_errors;  // franka_msgs/Errors flag names
  double finger_gap_m = 0;
  geometry::Pose object_base;
};

class FrankaStandIn {
 public:
  explicit FrankaStandIn(const FrankaStandInOptions& options);

  // The impedance controller's new equilibrium (end effector, base frame), stamped when
  // it was sent; ignored in a reflex, and when sent before the last reset (it was meant for
  // the scene before). Non-finite or non-unit poses are ignored too (a real controller
  // would fault).
  void set_equilibrium(const geometry::Pose& ee_base, std::chrono::system_clock::time_point stamp);
  // franka_gripper's move and grasp: false when refused (a width outside 0 to 0.08 m).
  bool gripper_move(double width_m);
  bool gripper_grasp(double width_m);
  // franka_control's error_recovery: clears a reflex. False when there was nothing to clear.
  bool error_recovery();
  void inject_reflex(const std::string& error_name);
  // Runs the 1 kHz control loop for `seconds`, the reflex checks after each tick.
  void advance(double seconds);
  // The home posture and the episode `seed` puts the object and goal at, as of `now`.
  Episode reset(std::uint64_t seed,
                std::chrono::system_clock::time_point now = std::chrono::system_clock::now());

  FrankaStandInState state() const;
  const SimulatedArm& arm() const { return arm_; }

 private:
  void reflex(const std::string& error_name);
  void apply_equilibrium();

  FrankaStandInOptions options_;
  SimulatedArm arm_;
  std::optional<geometry::Pose> pending_equilibrium_;  // the grip pose it asks for
  std::optional<geometry::Pose> equilibrium_grip_;     // the last one applied
  double gripper_width_m_;
  std::vector<std::string> errors_;
  std::chrono::system_clock::time_point last_reset_{};
};

}  // namespace pnp::arm_sim
