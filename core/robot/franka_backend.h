#pragma once
// A Franka Emika Panda behind franka_ros as a controller's arm (robot::ArmBackend): what
// pnp-franka-bridge drives. Its ROS side hands in franka_state_controller's FrankaState,
// the gripper's width and a tracker's object pose, and carries out what this asks of
// franka_ros (FrankaCommands): an equilibrium pose for the Cartesian impedance controller
// at the bridge's streaming rate, gripper moves and grasps, error recovery. No ROS here:
// the same logic serves a ROS 2 or libfranka side later.
//
// The arm's own faults latch: a robot mode other than "move", any current error, or a
// state topic that stalls puts the arm into a stop whose reason names them
// (BackendReading::fault), which the controller records as an emergency stop; only an
// operator's Resume clears it, and that Resume is what sends error recovery. Every pose
// here names the grip point (sim::kGripPointFromFlange_m from the flange), whatever
// end-effector frame franka_control was configured with (F_T_EE, read from each state).

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "geometry/rigid_transform.h"
#include "robot/arm_backend.h"
#include "robot/cartesian_motion.h"

namespace pnp::robot {

using SteadyTime = std::chrono::steady_clock::time_point;

// franka_msgs/FrankaState's robot_mode values.
enum class FrankaRobotMode : std::uint8_t {
  kOther = 0,
  kIdle = 1,
  kMove = 2,
  kGuiding = 3,
  kReflex = 4,
  kUserStopped = 5,
  kAutomaticErrorRecovery = 6,
};
std::string franka_robot_mode_name(std::uint8_t mode);  // "move", "reflex", ... or a number

// What the bridge uses of one FrankaState (matrices column-major, as franka_ros sends them).
struct FrankaStateSample {
  SteadyTime received{};
  std::array<double, 16> O_T_EE{};  // base to end effector, measured
  std::array<double, 16> F_T_EE{};  // flange to end effector: the configured EE frame
  std::array<double, kArmJointCount> q{};
  std::uint8_t robot_mode = 0;
  std::vector<std::string> current_errors;  // the names of the Errors flags that are set
};

struct TrackedObject {
  SteadyTime received{};
  geometry::Pose pose_base;  // the object's centre, in the arm's base frame
};

// What the backend asks of franka_ros; the ROS side sends each at once (non-blocking).
class FrankaCommands {
 public:
  virtual ~FrankaCommands() = default;
  // equilibrium_pose of the Cartesian impedance controller: the end effector's pose.
  virtual void send_equilibrium_pose(const geometry::Pose& ee_base) = 0;
  virtual void send_gripper_move(double width_m, double speed_m_per_s) = 0;
  virtual void send_gripper_grasp(double width_m, double epsilon_inner_m, double epsilon_outer_m,
                                  double speed_m_per_s, double force_n) = 0;
  virtual void send_error_recovery() = 0;
};

struct FrankaBackendOptions {
  double state_timeout_s = 0.1;       // no FrankaState for longer: the state topic stalled
  double object_timeout_s = 0.2;      // a tracker pose older than this is no pose
  double recovery_timeout_s = 5.0;    // error recovery that has not cleared by then latches again
  CartesianLimits motion;             // the equilibrium pose's own limits
  double tcp_from_flange_m = 0.0934;  // sim::kGripPointFromFlange_m
  // The hand: the Franka Hand's continuous grasp force and a speed well inside its 0.1 m/s;
  // a commanded width this much below (above) the last goal closes (opens) it.
  double grasp_force_n = 70;
  double gripper_speed_m_per_s = 0.1;
  double gripper_deadband_m = 0.005;
  double max_gripper_width_m = 0.08;
  // INVALID_ARGUMENT naming the field.
  void validate() const;
};

class FrankaBackend final : public ArmBackend {
 public:
  // `commands` must outlive the backend.
  FrankaBackend(FrankaCommands& commands, const FrankaBackendOptions& options);

  // From the ROS side, under the controller's lock. A state that cannot be read (a
  // non-rigid O_T_EE or F_T_EE) latches a stop naming it.
  void on_state(const FrankaStateSample& sample);
  void on_gripper_width(double width_m) { gripper_width_m_ = width_m; }
  void on_object(const TrackedObject& object) { object_ = object; }
  // One tick of the streaming loop at `now`: staleness checked, the motion generator
  // advanced by `dt_s`, the equilibrium pose sent (nothing before the first state).
  void tick(SteadyTime now, double dt_s);

  // Something else is about to move the arm (a simulated scene reset): no equilibrium is
  // sent until rest_at_measured(), which then holds where the arm now is, with no target
  // and no gripper goal.
  void pause_streaming() { paused_ = true; }
  void rest_at_measured();
  // When the latest readable state arrived (nullopt: none yet).
  std::optional<SteadyTime> last_state_received() const;
  // When the tracker's latest pose arrived (nullopt: none yet).
  std::optional<SteadyTime> last_object_received() const {
    return object_ ? std::optional(object_->received) : std::nullopt;
  }

  BackendReading reading() const override;
  IntakeOutcome command(const ArmTarget& target) override;
  double default_max_speed_m_per_s() const override { return options_.motion.speed_m_per_s; }
  void stop() override;
  void resume() override;

 private:
  enum class Phase { kWaitingForState, kRunning, kStopped, kLatched, kRecovering };
  void latch(std::string reason);
  std::optional<std::string> fault_in(const FrankaStateSample& sample) const;
  geometry::Pose grip_from_ee(const geometry::Pose& ee) const;
  geometry::Pose ee_from_grip(const geometry::Pose& grip) const;
  void command_gripper(double width_m);

  FrankaCommands& commands_;
  const FrankaBackendOptions options_;
  Phase phase_ = Phase::kWaitingForState;
  std::string fault_;
  std::optional<FrankaStateSample> state_;
  geometry::RigidTransform flange_from_ee_;  // from the latest state's F_T_EE
  geometry::Pose measured_grip_;
  std::optional<CartesianMotion> motion_;  // from the first state on
  SteadyTime now_{};
  SteadyTime recovery_started_{};
  bool tracking_ = false;  // a target was accepted since the last hold
  bool paused_ = false;    // pause_streaming(): nothing is sent
  double gripper_width_m_ = 0;
  std::optional<double> gripper_goal_m_;  // the last width a move or grasp was sent for
  std::optional<TrackedObject> object_;
};

}  // namespace pnp::robot
