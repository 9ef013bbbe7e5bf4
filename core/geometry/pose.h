#pragma once
// A rigid pose: where a frame's origin is (metres) and how it is turned, both expressed in
// the parent frame that the code handling it names. The quaternion rotates vectors of the
// posed frame into the parent frame, as MuJoCo's and Eigen's do.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pnp::geometry {

struct Pose {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

inline bool is_finite(const Pose& pose) {
  return pose.position_m.allFinite() && pose.orientation.coeffs().allFinite();
}

// The angle (rad, in [0, pi]) of the rotation that turns `a` into `b`. Both are
// normalised first, and q and -q count as the same orientation.
inline double rotation_angle_rad(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.normalized().angularDistance(b.normalized());
}

}  // namespace pnp::geometry
