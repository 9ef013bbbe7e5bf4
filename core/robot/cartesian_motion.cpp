#include "robot/cartesian_motion.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp::robot {
namespace {

void require_positive(double value, const char* field) {
  if (!(std::isfinite(value) && value > 0)) {
    throw_invalid_argument(field, "a positive, finite value", std::to_string(value));
  }
}

// `v` scaled down as one vector to at most `limit` long.
Eigen::Vector3d clamp_norm(const Eigen::Vector3d& v, double limit) {
  const double n = v.norm();
  return n > limit ? Eigen::Vector3d(v * (limit / n)) : v;
}

// Closer than this to the target, at less than one tick's worth of speed, is there.
constexpr double kArrival_m = 1e-6;
constexpr double kArrival_rad = 1e-6;
constexpr double kSettleSpeed_m_per_s = 1e-4;
// The velocity loop's bandwidth (a 10 ms time constant, five times the 2 ms the jerk limit
// takes to ramp the acceleration up to its limit), and the position loop's, a quarter of
// it: a critically damped cascade.
constexpr double kVelocityGain_per_s = 100;
constexpr double kPositionGain_per_s = 25;

}  // namespace

void CartesianLimits::validate() const {
  require_positive(speed_m_per_s, "speed_m_per_s");
  require_positive(acceleration_m_per_s2, "acceleration_m_per_s2");
  require_positive(jerk_m_per_s3, "jerk_m_per_s3");
  require_positive(angular_speed_rad_per_s, "angular_speed_rad_per_s");
  require_positive(angular_acceleration_rad_per_s2, "angular_acceleration_rad_per_s2");
  if (!(braking_share > 0 && braking_share <= 1)) {
    throw_invalid_argument("braking_share", "a share in (0, 1]", std::to_string(braking_share));
  }
}

CartesianMotion::CartesianMotion(const geometry::Pose& start, const CartesianLimits& limits)
    : limits_(limits), setpoint_(start), target_(start), max_speed_m_per_s_(limits.speed_m_per_s) {
  limits_.validate();
}

void CartesianMotion::set_target(const geometry::Pose& target, double max_speed_m_per_s) {
  target_ = target;
  max_speed_m_per_s_ = max_speed_m_per_s > 0 ? std::min(max_speed_m_per_s, limits_.speed_m_per_s)
                                             : limits_.speed_m_per_s;
  braking_ = false;
}

void CartesianMotion::stop() {
  braking_ = true;
}

void CartesianMotion::reset(const geometry::Pose& pose) {
  setpoint_ = pose;
  target_ = pose;
  velocity_.setZero();
  acceleration_.setZero();
  angular_speed_rad_per_s_ = 0;
  braking_ = false;
}

bool CartesianMotion::at_rest() const {
  return velocity_.isZero() && angular_speed_rad_per_s_ == 0;
}

void CartesianMotion::advance(double dt_s) {
  require_positive(dt_s, "dt_s");
  advance_translation(dt_s);
  advance_rotation(dt_s);
  if (braking_ && at_rest()) {
    target_ = setpoint_;
    braking_ = false;
  }
}

void CartesianMotion::advance_translation(double dt_s) {
  const Eigen::Vector3d to_target = target_.position_m - setpoint_.position_m;
  const double distance = to_target.norm();
  Eigen::Vector3d wanted = Eigen::Vector3d::Zero();  // the velocity this tick aims for
  if (!braking_ && distance > kArrival_m) {
    // The fastest speed from which the set point still stops at the target, and near it
    // a speed proportional to the distance: a cascade the jerk limit can follow without
    // chattering about the target.
    const double stoppable =
        std::sqrt(2 * limits_.braking_share * limits_.acceleration_m_per_s2 * distance);
    const double approach = kPositionGain_per_s * distance;
    wanted = to_target / distance * std::min({max_speed_m_per_s_, stoppable, approach});
  }
  const Eigen::Vector3d accel_wanted =
      clamp_norm(kVelocityGain_per_s * (wanted - velocity_), limits_.acceleration_m_per_s2);
  acceleration_ += clamp_norm(accel_wanted - acceleration_, limits_.jerk_m_per_s3 * dt_s);
  velocity_ = clamp_norm(velocity_ + acceleration_ * dt_s, limits_.speed_m_per_s);
  setpoint_.position_m += velocity_ * dt_s;
  // Arrived, or braked to rest: settle exactly, so that holding sends a constant pose.
  const double settle_speed = kSettleSpeed_m_per_s;
  const bool arrived = (target_.position_m - setpoint_.position_m).norm() <= kArrival_m;
  if (velocity_.norm() <= settle_speed && (braking_ || arrived)) {
    if (!braking_) setpoint_.position_m = target_.position_m;
    velocity_.setZero();
    acceleration_.setZero();
  }
}

void CartesianMotion::advance_rotation(double dt_s) {
  const double angle = setpoint_.orientation.angularDistance(target_.orientation);
  double wanted = 0;
  if (!braking_ && angle > kArrival_rad) {
    wanted = std::min(
        limits_.angular_speed_rad_per_s,
        std::sqrt(2 * limits_.braking_share * limits_.angular_acceleration_rad_per_s2 * angle));
  }
  const double max_change = limits_.angular_acceleration_rad_per_s2 * dt_s;
  angular_speed_rad_per_s_ +=
      std::clamp(wanted - angular_speed_rad_per_s_, -max_change, max_change);
  if (angle <= kArrival_rad) {
    setpoint_.orientation = target_.orientation;
    angular_speed_rad_per_s_ = braking_ ? std::max(0.0, angular_speed_rad_per_s_) : 0;
    if (angular_speed_rad_per_s_ <= max_change) angular_speed_rad_per_s_ = 0;
    return;
  }
  const double step = std::min(angular_speed_rad_per_s_ * dt_s, angle);
  setpoint_.orientation = setpoint_.orientation.slerp(step / angle, target_.orientation);
  if (angular_speed_rad_per_s_ <= max_change && wanted == 0) angular_speed_rad_per_s_ = 0;
}

}  // namespace pnp::robot
