#pragma once
// A Cartesian motion generator: the set point a controller streams to an arm that does not
// limit its own motion (franka_ros's Cartesian impedance controller springs towards
// whatever equilibrium pose it is given). Every tick the set point moves towards the
// latest target within the Panda's published Cartesian limits: speed, acceleration and
// jerk of the translation, speed and acceleration of the rotation. It slows down in time
// to stop at the target (no overshoot at these limits), and a stop brakes along the
// current direction within the same limits. No allocation per tick.

#include "geometry/pose.h"

namespace pnp::robot {

// Franka's "Limits for Panda" (Cartesian space), the motion generator's own bounds.
struct CartesianLimits {
  double speed_m_per_s = 1.7;
  double acceleration_m_per_s2 = 13.0;
  double jerk_m_per_s3 = 6500.0;
  double angular_speed_rad_per_s = 2.5;
  double angular_acceleration_rad_per_s2 = 25.0;
  // Braking plans with this share of the acceleration limit: the rest absorbs the jerk
  // limit's ramp, so the set point stops at the target instead of passing it.
  double braking_share = 0.5;
  // INVALID_ARGUMENT naming the field unless every value is positive and finite and the
  // share is in (0, 1].
  void validate() const;
};

class CartesianMotion {
 public:
  // Starts at rest at `start`. INVALID_ARGUMENT for invalid limits.
  CartesianMotion(const geometry::Pose& start, const CartesianLimits& limits);

  // A new target, reached at no more than `max_speed_m_per_s` (capped to the limit; 0:
  // the limit). The motion continues from the current set point and velocity.
  void set_target(const geometry::Pose& target, double max_speed_m_per_s = 0);
  // Brake to rest within the limits, then hold there (the target becomes that pose).
  void stop();
  // Rest at `pose` at once: after a reflex, or when the arm was moved by hand.
  void reset(const geometry::Pose& pose);
  // One tick of `dt_s` seconds (positive, finite).
  void advance(double dt_s);

  const geometry::Pose& setpoint() const { return setpoint_; }
  const geometry::Pose& target() const { return target_; }
  const Eigen::Vector3d& velocity() const { return velocity_; }
  const Eigen::Vector3d& acceleration() const { return acceleration_; }
  bool at_rest() const;

 private:
  void advance_translation(double dt_s);
  void advance_rotation(double dt_s);

  CartesianLimits limits_;
  geometry::Pose setpoint_;
  geometry::Pose target_;
  double max_speed_m_per_s_;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration_ = Eigen::Vector3d::Zero();
  double angular_speed_rad_per_s_ = 0;  // along the shortest arc to the target
  bool braking_ = false;
};

}  // namespace pnp::robot
