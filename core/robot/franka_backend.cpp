#include "robot/franka_backend.h"

#include <cmath>

#include "common/error.h"

namespace pnp::robot {
namespace {

double seconds_between(SteadyTime from, SteadyTime to) {
  return std::chrono::duration<double>(to - from).count();
}

geometry::RigidTransform transform_of(const std::array<double, 16>& column_major,
                                      std::string_view field) {
  return geometry::RigidTransform::from_matrix(
      Eigen::Map<const Eigen::Matrix4d>(column_major.data()), field);
}

geometry::RigidTransform transform_of(const geometry::Pose& pose) {
  return geometry::RigidTransform::from_matrix(geometry::to_matrix(pose), "pose");
}

geometry::Pose pose_of(const geometry::RigidTransform& t) {
  return geometry::pose_from_matrix(t.matrix());
}

void require_positive(double value, const char* field) {
  if (!(std::isfinite(value) && value > 0)) {
    throw_invalid_argument(field, "a positive, finite value", std::to_string(value));
  }
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::string franka_robot_mode_name(std::uint8_t mode) {
  switch (static_cast<FrankaRobotMode>(mode)) {
    case FrankaRobotMode::kOther:
      return "other";
    case FrankaRobotMode::kIdle:
      return "idle";
    case FrankaRobotMode::kMove:
      return "move";
    case FrankaRobotMode::kGuiding:
      return "guiding";
    case FrankaRobotMode::kReflex:
      return "reflex";
    case FrankaRobotMode::kUserStopped:
      return "user stopped";
    case FrankaRobotMode::kAutomaticErrorRecovery:
      return "automatic error recovery";
  }
  return std::to_string(mode);
}

void FrankaBackendOptions::validate() const {
  require_positive(state_timeout_s, "state_timeout_s");
  require_positive(object_timeout_s, "object_timeout_s");
  require_positive(recovery_timeout_s, "recovery_timeout_s");
  require_positive(tcp_from_flange_m, "tcp_from_flange_m");
  require_positive(grasp_force_n, "grasp_force_n");
  require_positive(gripper_speed_m_per_s, "gripper_speed_m_per_s");
  require_positive(gripper_deadband_m, "gripper_deadband_m");
  require_positive(max_gripper_width_m, "max_gripper_width_m");
  motion.validate();
}

FrankaBackend::FrankaBackend(FrankaCommands& commands, const FrankaBackendOptions& options)
    : commands_(commands), options_(options) {
  options_.validate();
}

std::optional<std::string> FrankaBackend::fault_in(const FrankaStateSample& sample) const {
  std::string why;
  if (sample.robot_mode != static_cast<std::uint8_t>(FrankaRobotMode::kMove)) {
    why = "robot mode " + franka_robot_mode_name(sample.robot_mode) + " (expected move)";
  }
  if (!sample.current_errors.empty()) {
    why +=
        (why.empty() ? "" : "; ") + std::string("current errors: ") + joined(sample.current_errors);
  }
  if (why.empty()) return std::nullopt;
  return "franka: " + why;
}

geometry::Pose FrankaBackend::grip_from_ee(const geometry::Pose& ee) const {
  // base_from_grip = base_from_ee * ee_from_flange * flange_from_grip
  const geometry::RigidTransform flange_from_grip = geometry::RigidTransform::from_translation_rpy(
      {0, 0, options_.tcp_from_flange_m}, 0, 0, 0, "tcp_from_flange_m");
  return pose_of(transform_of(ee) * flange_from_ee_.inverse() * flange_from_grip);
}

geometry::Pose FrankaBackend::ee_from_grip(const geometry::Pose& grip) const {
  const geometry::RigidTransform grip_from_flange = geometry::RigidTransform::from_translation_rpy(
      {0, 0, -options_.tcp_from_flange_m}, 0, 0, 0, "tcp_from_flange_m");
  return pose_of(transform_of(grip) * grip_from_flange * flange_from_ee_);
}

void FrankaBackend::latch(std::string reason) {
  if (phase_ == Phase::kLatched) return;  // the first reason stands
  phase_ = Phase::kLatched;
  fault_ = std::move(reason);
  tracking_ = false;
  // Hold where the arm is: the arm stopped itself (a reflex) or may have moved by hand.
  if (motion_) motion_->reset(measured_grip_);
}

void FrankaBackend::on_state(const FrankaStateSample& sample) {
  geometry::RigidTransform flange_from_ee;
  geometry::Pose measured;
  try {
    flange_from_ee = transform_of(sample.F_T_EE, "F_T_EE");
    flange_from_ee_ = flange_from_ee;
    measured = grip_from_ee(pose_of(transform_of(sample.O_T_EE, "O_T_EE")));
  } catch (const Error& e) {
    latch(std::string("franka: unreadable state: ") + e.what());
    return;
  }
  state_ = sample;
  measured_grip_ = measured;
  if (!motion_) motion_.emplace(measured, options_.motion);
  if (phase_ == Phase::kWaitingForState) phase_ = Phase::kRunning;
  const auto fault = fault_in(sample);
  if (phase_ == Phase::kRecovering && !fault) {
    phase_ = Phase::kRunning;
    motion_->reset(measured);
    return;
  }
  if (fault && phase_ != Phase::kRecovering) latch(*fault);
}

void FrankaBackend::tick(SteadyTime now, double dt_s) {
  now_ = now;
  if (!state_) return;  // nothing is sent before the arm has said where it is
  const double age_s = seconds_between(state_->received, now);
  if (age_s > options_.state_timeout_s && phase_ != Phase::kLatched) {
    latch("franka: the state topic stalled (no FrankaState for " + std::to_string(age_s) +
          " s, state_timeout_s " + std::to_string(options_.state_timeout_s) + ")");
  }
  if (phase_ == Phase::kRecovering &&
      seconds_between(recovery_started_, now) > options_.recovery_timeout_s) {
    const auto fault = fault_in(*state_);
    phase_ = Phase::kLatched;  // a fresh latch: the operator sees why again
    fault_ = "franka: error recovery did not clear the arm within " +
             std::to_string(options_.recovery_timeout_s) + " s" +
             (fault ? " (" + *fault + ")" : std::string());
  }
  if (paused_) return;
  motion_->advance(dt_s);
  commands_.send_equilibrium_pose(ee_from_grip(motion_->setpoint()));
}

BackendReading FrankaBackend::reading() const {
  BackendReading r;
  if (!motion_) {  // no readable state yet
    r.mode = phase_ == Phase::kLatched ? ArmMode::kStopped : ArmMode::kFault;
    r.fault = phase_ == Phase::kLatched ? fault_ : "franka: no FrankaState received yet";
    return r;
  }
  switch (phase_) {
    case Phase::kWaitingForState:
      r.mode = ArmMode::kFault;
      r.fault = "franka: no FrankaState received yet";
      return r;
    case Phase::kStopped:
    case Phase::kLatched:
      r.mode = ArmMode::kStopped;
      break;
    case Phase::kRecovering:
      r.mode = ArmMode::kHolding;
      break;
    case Phase::kRunning:
      r.mode = !tracking_           ? ArmMode::kIdle
               : motion_->at_rest() ? ArmMode::kHolding
                                    : ArmMode::kTracking;
      break;
  }
  if (phase_ == Phase::kLatched) r.fault = fault_;
  r.tcp_base = measured_grip_;
  r.commanded_base = motion_->setpoint();
  r.setpoint_base = motion_->setpoint();
  r.target_base = motion_->target();
  r.finger_gap_m = gripper_width_m_;
  r.joint_positions_rad = state_->q;
  if (object_ && seconds_between(object_->received, now_) <= options_.object_timeout_s) {
    r.object_base = object_->pose_base;
  }
  return r;
}

IntakeOutcome FrankaBackend::command(const ArmTarget& target) {
  switch (phase_) {
    case Phase::kWaitingForState:
      return {ControllerStatus::kStopped, "franka: no FrankaState received yet"};
    case Phase::kStopped:
    case Phase::kLatched:
      return {ControllerStatus::kStopped, fault_.empty() ? "the arm is stopped" : fault_};
    case Phase::kRecovering:
      return {ControllerStatus::kStopped, "franka: error recovery under way"};
    case Phase::kRunning:
      break;
  }
  if (!target.position_m.allFinite() ||
      !(std::abs(target.orientation.norm() - 1.0) <= kUnitQuaternionTolerance)) {
    return {ControllerStatus::kInvalidTarget,
            "pose: expected a finite position and a unit quaternion"};
  }
  if (!(target.gripper_width_m >= 0 && target.gripper_width_m <= options_.max_gripper_width_m)) {
    return {ControllerStatus::kInvalidTarget,
            "gripper_width_m: expected 0 to " + std::to_string(options_.max_gripper_width_m) +
                ", got " + std::to_string(target.gripper_width_m)};
  }
  motion_->set_target({target.position_m, target.orientation.normalized()},
                      target.max_speed_m_per_s);
  tracking_ = true;
  command_gripper(target.gripper_width_m);
  return {};
}

// A closing command grasps (whatever the object's width: epsilons from 0 to the hand's
// full opening), an opening one moves; small changes send nothing, so the hand is not
// sent a new goal every policy step.
void FrankaBackend::command_gripper(double width_m) {
  if (gripper_goal_m_ && std::abs(width_m - *gripper_goal_m_) < options_.gripper_deadband_m) {
    return;
  }
  const bool closing = gripper_goal_m_ ? width_m < *gripper_goal_m_ : width_m < gripper_width_m_;
  if (closing) {
    commands_.send_gripper_grasp(width_m, width_m, options_.max_gripper_width_m - width_m,
                                 options_.gripper_speed_m_per_s, options_.grasp_force_n);
  } else {
    commands_.send_gripper_move(width_m, options_.gripper_speed_m_per_s);
  }
  gripper_goal_m_ = width_m;
}

void FrankaBackend::rest_at_measured() {
  paused_ = false;
  if (motion_) motion_->reset(measured_grip_);
  tracking_ = false;
  gripper_goal_m_.reset();
}

std::optional<SteadyTime> FrankaBackend::last_state_received() const {
  if (!state_) return std::nullopt;
  return state_->received;
}

void FrankaBackend::stop() {
  if (phase_ == Phase::kRunning || phase_ == Phase::kRecovering) phase_ = Phase::kStopped;
  tracking_ = false;
  if (motion_) motion_->stop();
}

void FrankaBackend::resume() {
  if (phase_ == Phase::kStopped) {
    phase_ = Phase::kRunning;
    if (motion_) motion_->reset(motion_->setpoint());
    return;
  }
  if (phase_ != Phase::kLatched) return;
  fault_.clear();
  if (state_ && fault_in(*state_)) {
    // Only here, on an operator's Resume: franka_control's error_recovery action.
    commands_.send_error_recovery();
    phase_ = Phase::kRecovering;
    recovery_started_ = now_;
  } else {
    phase_ = state_ ? Phase::kRunning : Phase::kWaitingForState;  // a stall that has passed
  }
  if (motion_) motion_->reset(measured_grip_);
}

}  // namespace pnp::robot
