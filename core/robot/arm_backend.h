#pragma once
// The arm behind a controller's network side. The controller's rules (robot/
// arm_controller.h: leases, streams, sequence, frame and freshness, its own limits,
// stops) are the same whatever moves the hand; an ArmBackend is what moves it:
// pnp-robot-sim's simulated Panda (arm_sim/simulated_arm_backend.h), or a Franka
// through franka_ros (pnp-franka-bridge). A backend refuses what the arm itself cannot do
// (a pose out of reach, a joint limit, a stop in force); everything else was checked
// before it is asked. Not thread-safe: the controller calls it under its own lock.

#include <array>
#include <optional>
#include <string>

#include "geometry/pose.h"

namespace pnp::robot {

inline constexpr int kArmJointCount = 7;  // the Panda's, as every backend here
// | |q| - 1 | allowed for a target's orientation; beyond it the target is invalid.
inline constexpr double kUnitQuaternionTolerance = 1e-3;

// What the arm is doing.
enum class ArmMode {
  kIdle,      // no target yet: holding where it is
  kTracking,  // moving towards the latest target
  kHolding,   // the latest target reached or abandoned: holding
  kStopped,   // stopped (stop()): targets refused until resume()
  kFault,     // the arm faulted (a reflex, a physics failure): nothing moves
};

// The outcome of a request, or the controller's condition, as the protocol reports it.
enum class ControllerStatus {
  kOk,
  kInvalidTarget,
  kUnreachable,
  kJointLimit,
  kStopped,
  kLeaseLost,
  kOutsideLimits,  // the controller's own workspace, table plane or step limit
  kStale,          // the target's stamp is too old (or missing)
};

struct ArmTarget {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // base frame
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  double gripper_width_m = 0;
  double max_speed_m_per_s = 0;  // 0: the arm's default
};

struct IntakeOutcome {
  ControllerStatus status = ControllerStatus::kOk;
  std::string error;  // why, when not kOk
  bool accepted() const { return status == ControllerStatus::kOk; }
};

// What the controller reads of its arm, every pose in the base frame at the grip point.
struct BackendReading {
  ArmMode mode = ArmMode::kIdle;
  geometry::Pose tcp_base;  // measured
  // What the motion generator commands now (libfranka's O_T_EE_c): the base for the next
  // target's step limit.
  geometry::Pose commanded_base;
  geometry::Pose setpoint_base;  // the interpolated set point followed now
  geometry::Pose target_base;    // the latest accepted target (libfranka's O_T_EE_d)
  double finger_gap_m = 0;       // distance between the pads
  std::array<double, kArmJointCount> joint_positions_rad{};
  // Where the object is, when the backend perceives it (a simulation always; a real arm
  // through a tracker).
  std::optional<geometry::Pose> object_base;
  std::string fault;  // kFault: why, in the arm's own words
};

class ArmBackend {
 public:
  virtual ~ArmBackend() = default;

  virtual BackendReading reading() const = 0;
  // Starts the arm towards `target` (speed already capped by the controller), or refuses
  // it changing nothing: kInvalidTarget, kUnreachable, kJointLimit or kStopped, with why.
  virtual IntakeOutcome command(const ArmTarget& target) = 0;
  // The speed a target asking for none is driven at.
  virtual double default_max_speed_m_per_s() const = 0;
  // A controlled stop: decelerate within the arm's limits and hold; refuse targets.
  virtual void stop() = 0;
  // Leaves a stop holding the measured pose; nothing when not stopped.
  virtual void resume() = 0;
  // Once per target the controller answered, taken in or refused: a lockstep simulation
  // advances one policy period (time passes for a real arm too); a real arm's time is its
  // own.
  virtual void after_target() {}
};

}  // namespace pnp::robot
