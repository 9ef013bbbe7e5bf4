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

// The homogeneous 4x4 matrix of `pose` (its orientation normalised), and back. No checks:
// a matrix from outside goes through RigidTransform::from_matrix first.
inline Eigen::Matrix4d to_matrix(const Pose& pose) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = pose.orientation.normalized().toRotationMatrix();
  m.topRightCorner<3, 1>() = pose.position_m;
  return m;
}
inline Pose pose_from_matrix(const Eigen::Matrix4d& m) {
  return {m.topRightCorner<3, 1>(),
          Eigen::Quaterniond(Eigen::Matrix3d(m.topLeftCorner<3, 3>())).normalized()};
}

}  // namespace pnp::geometry
