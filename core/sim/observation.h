#pragma once
// The 25-value observation of the original Fetch environment, index by index (see
// docs/OBSERVATION.md for units). All positions are world-frame metres; velocities are
// world-frame and multiplied by the step duration (0.04 s), so they read as metres (or
// radians) per step.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace pnp::sim {

inline constexpr int kObservationSize = 25;
inline constexpr int kGoalSize = 3;
inline constexpr int kActionSize = 4;

using Observation = Eigen::Matrix<double, kObservationSize, 1>;
using Action = Eigen::Vector4d;  // xyz in [-1, 1] (x 0.05 m per step), gripper in [-1, 1]
using Goal = Eigen::Vector3d;

namespace obs {
inline constexpr int kGripperPos = 0;     // 0-2   grip site position
inline constexpr int kObjectPos = 3;      // 3-5   object centre position
inline constexpr int kObjectRelPos = 6;   // 6-8   object - gripper position
inline constexpr int kFingerPos = 9;      // 9-10  finger joint positions (left, right)
inline constexpr int kObjectEuler = 11;   // 11-13 object orientation, roll pitch yaw
inline constexpr int kObjectRelVel = 14;  // 14-16 object - gripper linear velocity x dt
inline constexpr int kObjectAngVel = 17;  // 17-19 object angular velocity x dt
inline constexpr int kGripperVel = 20;    // 20-22 gripper linear velocity x dt
inline constexpr int kFingerVel = 23;     // 23-24 finger joint velocities x dt
}  // namespace obs

inline Eigen::Vector3d gripper_position(const Observation& o) {
  return o.segment<3>(obs::kGripperPos);
}
inline Eigen::Vector3d object_position(const Observation& o) {
  return o.segment<3>(obs::kObjectPos);
}
// The object-orientation entries: roll, pitch, yaw of R = Rz(yaw) Ry(pitch) Rx(roll).
inline Eigen::Vector3d roll_pitch_yaw(const Eigen::Matrix3d& r) {
  return {std::atan2(r(2, 1), r(2, 2)), std::asin(std::clamp(-r(2, 0), -1.0, 1.0)),
          std::atan2(r(1, 0), r(0, 0))};
}

// Distance between the finger pads (m): the sum of the two finger joint positions.
inline double finger_gap(const Observation& o) {
  return o(obs::kFingerPos) + o(obs::kFingerPos + 1);
}

}  // namespace pnp::sim
