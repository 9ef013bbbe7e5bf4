#include "robot/perceived_observation.h"

#include <cmath>

#include "common/error.h"

namespace pnp::robot {
namespace {

constexpr double kFingerGapTolerance_m = 0.02;

void require_finite(const PerceivedState& s) {
  const bool finite = s.gripper_m.allFinite() && std::isfinite(s.finger_gap_m) &&
                      s.object_m.allFinite() && s.object_orientation.coeffs().allFinite();
  if (!finite)
    throw_invalid_argument("perceived state", "finite values", "a NaN or infinite value");
  // Fingers closed on nothing read below zero: the simulated fingers (the stand-in's and
  // the training environment's, whose observation passes it on unchanged) press past their
  // soft joint limit, by up to ~12 mm when a learned gripper squeezes hard. Such a reading
  // is kept as it is; only a gap further below zero than 2 cm is refused as a bad reading.
  if (s.finger_gap_m < -kFingerGapTolerance_m)
    throw_invalid_argument("finger_gap_m", "a gap >= -0.02 m", std::to_string(s.finger_gap_m));
  if (std::abs(s.object_orientation.norm() - 1.0) > 1e-3)
    throw_invalid_argument("object_orientation", "a unit quaternion",
                           "norm " + std::to_string(s.object_orientation.norm()));
}

// The rotation from `before` to `after` as a world-frame axis-angle vector.
Eigen::Vector3d rotation_change(const Eigen::Quaterniond& before, const Eigen::Quaterniond& after) {
  const Eigen::AngleAxisd delta(after.normalized() * before.normalized().conjugate());
  double angle = delta.angle();
  if (angle > M_PI) angle -= 2 * M_PI;  // the short way round
  return delta.axis() * angle;
}

}  // namespace

sim::Observation PerceivedObservation::update(const PerceivedState& state) {
  require_finite(state);
  namespace obs = sim::obs;
  sim::Observation o = sim::Observation::Zero();
  // The fingers move symmetrically: each finger joint is half the gap.
  const double finger = state.finger_gap_m / 2;
  o.segment<3>(obs::kGripperPos) = state.gripper_m;
  o.segment<3>(obs::kObjectPos) = state.object_m;
  o.segment<3>(obs::kObjectRelPos) = state.object_m - state.gripper_m;
  o(obs::kFingerPos) = o(obs::kFingerPos + 1) = finger;
  o.segment<3>(obs::kObjectEuler) =
      sim::roll_pitch_yaw(state.object_orientation.normalized().toRotationMatrix());
  if (previous_) {
    const PerceivedState& p = *previous_;
    const Eigen::Vector3d gripper_change = state.gripper_m - p.gripper_m;
    o.segment<3>(obs::kObjectRelVel) = (state.object_m - p.object_m) - gripper_change;
    o.segment<3>(obs::kObjectAngVel) =
        rotation_change(p.object_orientation, state.object_orientation);
    o.segment<3>(obs::kGripperVel) = gripper_change;
    o(obs::kFingerVel) = o(obs::kFingerVel + 1) = finger - p.finger_gap_m / 2;
  }
  previous_ = state;
  return o;
}

}  // namespace pnp::robot
