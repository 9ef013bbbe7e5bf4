#pragma once
// A simulated Franka Panda driven the way the real arm is: Cartesian TCP pose targets in
// the robot's base frame (body panda_link0) arrive at the policy's rate (25 Hz). Each
// accepted target starts a segment from the current commanded pose (linear position,
// slerp orientation) over one policy period, longer if a speed limit demands it. Every
// 1 ms tick: the segment's set point -> a warm-started damped-least-squares IK step -> a
// joint reference that follows the IK solution within the joint position, velocity and
// acceleration limits -> computed torque (tau = M(q) (qdd_ref + Kp e + Kd de) + bias,
// clamped to the Panda's torque limits) written to qfrc_applied -> mj_step. The fingers
// are the model's position actuators, coupled as a Franka Hand's are (the MJCF's
// "fingers_coupled", off in training). The mocap weld that drags the gripper in training
// is disabled: nothing here teleports the arm.
//
// The world is the training world (same MJCF, home pose, and object and goal for an
// episode seed as sim::PickPlaceEnv) stepped at 1 ms. Not thread-safe: one owner calls
// everything.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "common/rng.h"
#include "geometry/pose.h"
#include "geometry/rigid_transform.h"
#include "robot/arm_backend.h"
#include "sim/environment.h"
#include "sim/mujoco_data.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_model.h"
#include "sim/world_profile.h"

namespace pnp::arm_sim {

using robot::kUnitQuaternionTolerance;

inline constexpr int kJoints = sim::kArmJoints;
static_assert(kJoints == robot::kArmJointCount);
inline constexpr double kControlPeriod_s = 0.001;  // the controller's 1 kHz tick
using JointVector = std::array<double, kJoints>;

// The arm and hand are the Panda's, whatever a world profile gives a mocap-driven arm
// (gym's Fetch: joint damping 50 and armature 1, 4 kg fingers with armature 100 and no
// force limit). Joints and fingers: MuJoCo Menagerie's Panda (franka_emika_panda/
// panda.xml, class "panda", its masses from Franka's published model); the grasp force:
// the Franka Hand's continuous force (Franka's datasheet). The finger servo's gain and
// damping stay the world's.
inline constexpr double kPandaJointDamping = 1.0;   // N m s/rad
inline constexpr double kPandaJointArmature = 0.1;  // kg m^2 (also each finger's, kg)
inline constexpr double kPandaFingerMass_kg = 0.015;
inline constexpr double kFrankaHandForce_n = 70;

// The Panda's joint acceleration limits from Franka's datasheet, joints 1-7.
inline constexpr JointVector kPandaDatasheetAccelerations_rad_per_s2{15, 7.5, 10, 12.5, 15, 20, 20};
// The stand-in's accelerations as a multiple of the datasheet's: the datasheet's, so that
// the simulated arm cannot do what a real Panda would refuse with a reflex error. A policy
// trained on a mocap hand that reaches each target within 40 ms lags behind such an arm
// (the gateway can wait for it: GatewayConfig::max_arrival_wait_periods). Up to twice, for
// comparison (docs/RELIABILITY.md); three times demanded 88 N m on joint 1 for a 5 cm
// step, over its 87 N m.
inline constexpr double kDefaultAccelerationScale = 1.0;
inline constexpr double kMaxAccelerationScale = 2.0;
// The datasheet's accelerations times `scale`. INVALID_ARGUMENT naming `field` unless
// 0 < scale <= kMaxAccelerationScale.
JointVector arm_accelerations(double scale, std::string_view field = "acceleration_scale");

struct ArmControllerOptions {
  // Reference generator: each tick the joint reference tracks the IK solution's position
  // and velocity with a critically damped law of this bandwidth, its acceleration and
  // velocity each scaled down as one vector to the limits below (so the joints stay in
  // step and the TCP on its path). Linear interpolation alone asks for a velocity jump
  // at every 40 ms target; the reference is a trajectory the arm can follow.
  double reference_frequency_rad_per_s = 60.0;
  // Tracking loop (computed torque): tau = M(q) (qdd_ref + Kp e + Kd de) + bias, with
  // Kp = w^2 and Kd = 2 zeta w, so every joint has the same bandwidth. w dt = 0.1 keeps
  // the explicit 1 ms loop well inside its stability bound.
  double natural_frequency_rad_per_s = 100.0;
  double damping_ratio = 1.0;

  // Per-tick inverse kinematics: damped least-squares iterations from the previous
  // tick's solution. The set point moves at most a few mm per tick, so one is enough.
  int ik_iterations_per_tick = 1;
  double ik_damping = 1e-4;                   // lambda^2 of the damped pseudo-inverse
  double ik_nullspace_gain_per_tick = 0.002;  // pull towards the home posture (0.5 s)

  // Reachability check of each new target: a full IK solve from the measured posture.
  int reach_ik_iterations = 200;
  double reach_position_tolerance_m = 0.005;
  double reach_rotation_tolerance_rad = 0.05;
  double joint_limit_margin_rad = 1e-3;  // a solution this close to a limit "sits at" it

  // Segments: at least one policy period, longer if a speed limit demands it.
  double policy_period_s = 0.04;
  double default_max_speed_m_per_s = 1.7;  // the Panda's Cartesian translation limit
  double max_angular_speed_rad_per_s = 2.5;

  // Franka Panda limits, joints 1-7. The reference's velocity is held to
  // velocity_limit_fraction of the limits, headroom for the tracking error so that the
  // measured velocity stays within them.
  JointVector velocity_limits_rad_per_s{2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61};
  double velocity_limit_fraction = 0.9;
  // Accelerations: Franka's datasheet values times a scale (arm_accelerations below).
  // Jerks: the datasheet's (libfranka's rate limiter). Each is scaled down as one vector,
  // like the velocity.
  JointVector acceleration_limits_rad_per_s2 = arm_accelerations(kDefaultAccelerationScale);
  JointVector jerk_limits_rad_per_s3{7500, 3750, 5000, 6250, 7500, 10000, 10000};
  JointVector torque_limits_nm{87, 87, 87, 87, 12, 12, 12};
};

using geometry::Pose;

// What the arm is doing: robot::ArmMode, as every controller's arm reports it.
using robot::ArmMode;

enum class TargetCode { kAccepted, kInvalid, kUnreachable, kJointLimit, kStopped };

struct TargetStatus {
  TargetCode code = TargetCode::kAccepted;
  std::string message;    // empty when accepted; otherwise names the field or reason
  double duration_s = 0;  // accepted: how long the segment interpolates
  bool accepted() const { return code == TargetCode::kAccepted; }
};

struct Episode {
  Eigen::Vector3d goal_world;  // where the object centre must go
  Eigen::Vector3d goal_base;
};

// A scene as a real arm's sensors give it, in the base frame: where its grip point is,
// how far apart its fingers are, where the object is, and the goal.
struct ObservedScene {
  Pose tcp_base;
  double finger_gap_m = 0;
  Pose object_base;
  Eigen::Vector3d goal_base = Eigen::Vector3d::Zero();
};

struct ArmState {
  ArmMode mode = ArmMode::kIdle;
  double sim_time_s = 0;
  Pose tcp_world;  // measured (site "grip")
  Pose tcp_base;
  // What the motion generator commands now: the TCP pose of the joint reference the
  // torque loop tracks (libfranka's O_T_EE_c). It never runs ahead of what the limits
  // let the arm do, so "commanded + step" is the right base for the next target. The
  // measured TCP pose after reset(), stop() and resume().
  Pose commanded_base;
  Pose setpoint_base;       // the interpolated Cartesian set point the IK follows now
  Pose target_base;         // the latest accepted target (libfranka's O_T_EE_d)
  double finger_gap_m = 0;  // distance between the pads: the sum of the finger joints
  double commanded_gripper_width_m = 0;
  Pose object_world;
  Pose object_base;
  JointVector joint_positions{};
  JointVector joint_velocities{};
  JointVector joint_torques{};  // last commanded torques, after clamping
  // What the tracking loop asked for before clamping: above a torque limit means the
  // reference asked for more than the motors give (a real Panda would fault).
  JointVector joint_torques_demanded{};
};

class SimulatedArm {
 public:
  // Only Robot::kPanda (INVALID_ARGUMENT otherwise, or for non-positive options). Starts
  // in the episode of seed 0.
  SimulatedArm(sim::Robot robot, sim::ObjectShape object,
               sim::WorldProfile world = sim::WorldProfile::kPaper,
               const ArmControllerOptions& options = {});
  // The same over a world already loaded (shared, read-only), which must be the Panda's.
  explicit SimulatedArm(std::shared_ptr<const sim::WorldModel> world,
                        const ArmControllerOptions& options = {});
  SimulatedArm(const SimulatedArm&) = delete;
  SimulatedArm& operator=(const SimulatedArm&) = delete;

  // The initial state of PickPlaceEnv::reset(seed): home posture, the object and goal
  // that seed samples, fingers open. The commanded pose is the measured TCP pose.
  Episode reset(std::uint64_t seed);
  // The same from a random stream the caller keeps: the next episode layout `rng` draws
  // (PickPlaceEnv's fresh episode after a fault draws the same way).
  Episode reset(Rng& rng);

  // The arm put where `scene` says, at rest: the home posture moved by inverse kinematics
  // to its grip point's pose (unchanged if already there), the fingers at its gap (and
  // commanded open if more than half open, closed otherwise), the object at its pose. So
  // a dry run can play from what a real arm measured. INVALID_ARGUMENT naming the field
  // for a pose the arm cannot take or a non-finite value; nothing changes then.
  Episode reset_to(const ObservedScene& scene);

  // A TCP pose target in the base frame and a finger opening (0 to 0.08 m); max speed 0
  // means the default. Refusals change nothing.
  TargetStatus set_target(const Eigen::Vector3d& position_base_m,
                          const Eigen::Quaterniond& orientation_base, double gripper_width_m,
                          double max_speed_m_per_s = 0);

  // Runs floor(seconds / 1 ms) control ticks (plus rounding slack). INVALID_ARGUMENT for
  // a negative or non-finite duration. No heap allocation.
  void advance(double seconds);

  // A controlled stop (IEC 60204-1 category 2, as a Panda's stop): the joint reference
  // leaves its path's set point and brakes along its current direction within the
  // acceleration and jerk limits, then holds where it came to rest; targets are refused.
  void stop();
  void resume();  // leave the E-stop holding the measured TCP pose

  ArmState state() const;
  // Why the arm is in ArmMode::kFault (sim::detect_physics_fault after the tick that
  // failed); kNone otherwise.
  sim::PhysicsFault fault() const { return fault_; }
  bool task_success() const;  // sim::is_task_success on the object and the episode goal

  // Maps world coordinates to the base frame (body panda_link0), read from the model.
  const geometry::RigidTransform& base_from_world() const { return base_from_world_; }
  const geometry::RigidTransform& world_from_base() const { return world_from_base_; }
  const Episode& episode() const { return episode_; }
  double max_gripper_width_m() const { return 2 * world_->finger_range_m(); }
  const sim::WorldModel& world() const { return *world_; }
  const ArmControllerOptions& options() const { return options_; }

 private:
  struct ModelDeleter {
    void operator()(mjModel* m) const { mj_deleteModel(m); }
  };
  struct Segment {  // world frame
    Eigen::Vector3d from_position, to_position;
    Eigen::Quaterniond from_orientation, to_orientation;
    double start_s = 0, duration_s = 0;
    Pose at(double time_s) const;
    bool finished(double time_s) const { return time_s >= start_s + duration_s; }
  };

  TargetStatus check_reachable(const Pose& target_world);
  void tick();
  void update_joint_command();
  void brake_joint_command();
  // The speed from which `joint` can still stop within `distance_rad`, braking at its
  // planned share of its acceleration limit.
  double stoppable_speed(std::size_t joint, double distance_rad) const;
  // Moves the joint reference one tick with acceleration `accel` (rad/s^2), scaled down
  // as one vector to the jerk and acceleration limits, then the velocity limits.
  void integrate_joint_command(const Eigen::Matrix<double, kJoints, 1>& accel);
  void ik_iterations(const Pose& setpoint_world);
  void apply_joint_torques();
  void refresh_derived();
  Pose measured_tcp_world() const;
  Pose forward_kinematics(const JointVector& q);  // TCP pose, on the scratch data
  JointVector measured_joints() const;
  void hold_measured_pose();
  Episode start_at_rest(const Episode& episode);
  void set_gripper(double width_m);

  ArmControllerOptions options_;
  std::shared_ptr<const sim::WorldModel> world_;
  std::unique_ptr<mjModel, ModelDeleter> model_;
  std::unique_ptr<mjModel, ModelDeleter> unlimited_model_;  // arm joints without limits
  sim::DataPtr data_;
  sim::DataPtr scratch_;  // inverse kinematics: never stepped
  std::array<int, kJoints> qpos_adr_{};
  std::array<int, kJoints> dof_adr_{};
  JointVector lower_{}, upper_{};  // joint ranges shrunk by joint_limit_margin_rad
  JointVector home_{};
  geometry::RigidTransform base_from_world_, world_from_base_;

  // Preallocated per-tick buffers (nv-sized for MuJoCo's interfaces).
  std::vector<mjtNum> jacp_, jacr_, accel_, mass_accel_;

  Episode episode_;
  ArmMode mode_ = ArmMode::kIdle;
  sim::PhysicsFault fault_ = sim::PhysicsFault::kNone;
  Segment segment_;
  Pose target_world_;
  Pose commanded_world_;  // forward kinematics of command_q_, refreshed after each advance
  double gripper_width_m_ = 0;
  JointVector ik_q_{};       // the IK's own solution, warm start of the next tick
  JointVector command_q_{};  // the reference the torque loop tracks
  JointVector command_qd_{};
  JointVector command_qdd_{};
  JointVector torques_{};
  JointVector torques_demanded_{};
};

}  // namespace pnp::arm_sim
