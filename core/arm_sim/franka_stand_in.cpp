#include "arm_sim/franka_stand_in.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/error.h"
#include "sim/panda_hand.h"

namespace pnp::arm_sim {
namespace {

Eigen::Matrix4d grip_from_flange() {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(2, 3) = -sim::kGripPointFromFlange_m;
  return m;
}

}  // namespace

geometry::RigidTransform FrankaStandInOptions::default_flange_from_ee() {
  // franka_ros's default with a Franka Hand: NE_T_EE 0.1034 m along z, turned -pi/4.
  return geometry::RigidTransform::from_translation_rpy({0, 0, 0.1034}, 0, 0, -std::numbers::pi / 4,
                                                        "flange_from_ee");
}

FrankaStandIn::FrankaStandIn(const FrankaStandInOptions& options)
    : options_(options),
      arm_(sim::Robot::kPanda, options.object, options.world, options.arm),
      gripper_width_m_(arm_.max_gripper_width_m()) {
  if (!(options_.reflex_deviation_m > 0)) {
    throw_invalid_argument("reflex_deviation_m", "a positive distance",
                           std::to_string(options_.reflex_deviation_m));
  }
}

void FrankaStandIn::set_equilibrium(const geometry::Pose& ee_base,
                                    std::chrono::system_clock::time_point stamp) {
  if (!errors_.empty() || stamp < last_reset_) return;
  if (!geometry::is_finite(ee_base) ||
      !(std::abs(ee_base.orientation.norm() - 1.0) <= kUnitQuaternionTolerance)) {
    return;
  }
  // grip = ee * ee_from_flange * flange_from_grip
  const Eigen::Matrix4d grip = geometry::to_matrix(ee_base) *
                               options_.flange_from_ee.inverse().matrix() *
                               grip_from_flange().inverse();
  pending_equilibrium_ = geometry::pose_from_matrix(grip);
}

bool FrankaStandIn::gripper_move(double width_m) {
  if (!(width_m >= 0 && width_m <= arm_.max_gripper_width_m())) return false;
  gripper_width_m_ = width_m;
  if (equilibrium_grip_ && !pending_equilibrium_) pending_equilibrium_ = equilibrium_grip_;
  return true;
}

bool FrankaStandIn::gripper_grasp(double width_m) {
  // The fingers close on the object with the hand's force whatever the width asked for;
  // a Franka Hand's grasp succeeds when the width it ends at is within the epsilons.
  return gripper_move(std::max(0.0, std::min(width_m, arm_.max_gripper_width_m())));
}

bool FrankaStandIn::error_recovery() {
  if (errors_.empty()) return false;
  errors_.clear();
  arm_.resume();
  pending_equilibrium_.reset();
  equilibrium_grip_.reset();
  return true;
}

void FrankaStandIn::inject_reflex(const std::string& error_name) {
  reflex(error_name);
}

void FrankaStandIn::reflex(const std::string& error_name) {
  if (std::find(errors_.begin(), errors_.end(), error_name) == errors_.end()) {
    errors_.push_back(error_name);
  }
  arm_.stop();
  pending_equilibrium_.reset();
}

void FrankaStandIn::apply_equilibrium() {
  if (!pending_equilibrium_ || !errors_.empty()) return;
  const geometry::Pose grip = *pending_equilibrium_;
  pending_equilibrium_.reset();
  if ((grip.position_m - arm_.state().tcp_base.position_m).norm() > options_.reflex_deviation_m) {
    reflex("cartesian_reflex");
    return;
  }
  const TargetStatus taken =
      arm_.set_target(grip.position_m, grip.orientation, gripper_width_m_, 0);
  if (taken.code == TargetCode::kUnreachable || taken.code == TargetCode::kJointLimit) {
    reflex("cartesian_motion_generator_joint_position_limits_violation");
    return;
  }
  if (taken.accepted()) equilibrium_grip_ = grip;
}

void FrankaStandIn::advance(double seconds) {
  const auto ticks = static_cast<long>(std::floor(seconds / kControlPeriod_s + 1e-9));
  for (long k = 0; k < ticks; ++k) {
    apply_equilibrium();
    arm_.advance(kControlPeriod_s);
    if (arm_.state().mode == ArmMode::kFault) reflex("instability_detected");
  }
}

Episode FrankaStandIn::reset(std::uint64_t seed, std::chrono::system_clock::time_point now) {
  last_reset_ = now;
  errors_.clear();
  pending_equilibrium_.reset();
  equilibrium_grip_.reset();
  gripper_width_m_ = arm_.max_gripper_width_m();
  return arm_.reset(seed);
}

FrankaStandInState FrankaStandIn::state() const {
  const ArmState s = arm_.state();
  const Eigen::Matrix4d ee_from_grip =
      options_.flange_from_ee.inverse().matrix() * grip_from_flange().inverse();
  FrankaStandInState out;
  out.time_s = s.sim_time_s;
  out.flange_from_ee = options_.flange_from_ee.matrix();
  // ee = grip * grip_from_ee
  out.base_from_ee = geometry::to_matrix(s.tcp_base) * ee_from_grip.inverse();
  out.base_from_ee_desired = geometry::to_matrix(s.target_base) * ee_from_grip.inverse();
  out.q = s.joint_positions;
  out.dq = s.joint_velocities;
  out.tau = s.joint_torques;
  out.robot_mode = errors_.empty() ? kFrankaModeMove : kFrankaModeReflex;
  out.current_errors = errors_;
  out.finger_gap_m = s.finger_gap_m;
  out.object_base = s.object_base;
  return out;
}

}  // namespace pnp::arm_sim
