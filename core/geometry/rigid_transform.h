#pragma once
// A proper rigid transform (rotation and translation, no scale, shear or reflection) that
// maps coordinates of one frame into another: `parent_from_child.apply(p_child)` is
// `p_parent`. Names read right to left, so `a_from_b * b_from_c` is `a_from_c`.
//
// Every way in from outside (a 4x4 matrix, JSON) is checked: a calibration typed into a
// config file with a wrong sign in a rotation, a scale or a bottom row off would otherwise
// silently move a real arm somewhere else.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>
#include <string_view>

#include "geometry/pose.h"

namespace pnp::geometry {

class RigidTransform {
 public:
  // Accepted deviations of a matrix from a proper rigid transform.
  static constexpr double kBottomRowTolerance = 1e-9;
  static constexpr double kOrthonormalTolerance = 1e-6;  // max |R^T R - I|

  RigidTransform() = default;  // the identity
  static RigidTransform identity() { return {}; }

  // INVALID_ARGUMENT, naming `field` (and `field[i][j]` for an entry), unless `m` is finite,
  // its bottom row is 0 0 0 1 and its rotation part is orthonormal with det +1 (within
  // the tolerances above). R is kept as given when rigid to rounding (1e-12), else replaced
  // by the nearest exact rotation.
  static RigidTransform from_matrix(const Eigen::Matrix4d& m, std::string_view field);
  // R = Rz(yaw) Ry(pitch) Rx(roll), the convention of sim::roll_pitch_yaw; angles in rad.
  // INVALID_ARGUMENT naming `field` for a non-finite value.
  static RigidTransform from_translation_rpy(const Eigen::Vector3d& translation_m, double roll,
                                             double pitch, double yaw, std::string_view field);
  // A row-major 4x4 matrix: an array of 4 arrays of 4 numbers. INVALID_ARGUMENT naming
  // `field` (the shape) or `field[i][j]` (an entry), then the checks of from_matrix.
  static RigidTransform from_json(const nlohmann::json& json, std::string_view field);
  nlohmann::json to_json() const;  // the form from_json reads

  Eigen::Matrix4d matrix() const;
  const Eigen::Matrix3d& rotation() const { return rotation_; }
  const Eigen::Vector3d& translation_m() const { return translation_m_; }

  RigidTransform inverse() const;
  RigidTransform operator*(const RigidTransform& rhs) const;  // this after rhs

  Eigen::Vector3d apply(const Eigen::Vector3d& point_m) const;  // rotate, then translate
  Eigen::Vector3d rotate(const Eigen::Vector3d& vector) const;  // directions, velocities
  // The pose's position is mapped as a point; its orientation is turned by the rotation
  // and normalised.
  Pose apply(const Pose& pose) const;

 private:
  RigidTransform(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation_m)
      : rotation_(rotation), translation_m_(translation_m) {}

  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_m_ = Eigen::Vector3d::Zero();
};

}  // namespace pnp::geometry
