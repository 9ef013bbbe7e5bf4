#include "geometry/rigid_transform.h"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "common/error.h"

namespace pnp::geometry {
namespace {

[[noreturn]] void refuse(std::string_view field, std::string_view what) {
  throw Error(ErrorCode::kInvalidArgument, fmt::format("{}: {}", field, what));
}

std::string entry(std::string_view field, Eigen::Index i, Eigen::Index j) {
  return fmt::format("{}[{}][{}]", field, i, j);
}

std::string json_kind(const nlohmann::json& j) {
  if (j.is_array()) return fmt::format("an array of {}", j.size());
  if (j.is_object()) return "an object";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_null()) return "null";
  return j.dump();
}

// The rotation nearest to `r` (in the Frobenius norm): r is within 1e-6 of one, and
// keeping the exact rotation makes inverse() (the transpose) exact and stops composed
// transforms from drifting away from rigid.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& r) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace

RigidTransform RigidTransform::from_matrix(const Eigen::Matrix4d& m, std::string_view field) {
  for (Eigen::Index i = 0; i < 4; ++i) {
    for (Eigen::Index j = 0; j < 4; ++j) {
      if (!std::isfinite(m(i, j))) {
        throw_invalid_argument(entry(field, i, j), "a finite number", fmt::format("{}", m(i, j)));
      }
    }
  }
  const Eigen::RowVector4d bottom = m.row(3);
  if ((bottom - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kBottomRowTolerance) {
    refuse(field, fmt::format("bottom row is ({}, {}, {}, {}), expected (0, 0, 0, 1) within {:g}",
                              bottom(0), bottom(1), bottom(2), bottom(3), kBottomRowTolerance));
  }
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const double deviation = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kOrthonormalTolerance) {
    refuse(field, fmt::format("rotation part is not orthonormal (max |R^T R - I| = {:.3g}, "
                              "expected <= {:g}): a scale or shear is not a rigid transform",
                              deviation, kOrthonormalTolerance));
  }
  // Orthonormal leaves det = +1 or -1; -1 is a reflection, which no robot frame has.
  const double det = r.determinant();
  if (det < 0) {
    refuse(field, fmt::format("rotation part has det = {:.3g}, expected +1 (a reflection is "
                              "not a rotation)",
                              det));
  }
  // Already rigid to rounding: kept as it is, so that to_json/from_json round trips are
  // exact (projecting again would move the last bits each time).
  constexpr double kRoundingLevel = 1e-12;
  return RigidTransform(deviation <= kRoundingLevel ? r : nearest_rotation(r),
                        m.topRightCorner<3, 1>());
}

RigidTransform RigidTransform::from_translation_rpy(const Eigen::Vector3d& translation_m,
                                                    double roll, double pitch, double yaw,
                                                    std::string_view field) {
  if (!translation_m.allFinite() || !std::isfinite(roll) || !std::isfinite(pitch) ||
      !std::isfinite(yaw)) {
    throw_invalid_argument(
        field, "a finite translation and finite roll, pitch, yaw",
        fmt::format("translation ({}, {}, {}), rpy ({}, {}, {})", translation_m.x(),
                    translation_m.y(), translation_m.z(), roll, pitch, yaw));
  }
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return RigidTransform(r, translation_m);
}

RigidTransform RigidTransform::from_json(const nlohmann::json& json, std::string_view field) {
  constexpr std::string_view kShape = "a row-major 4x4 matrix (an array of 4 arrays of 4 numbers)";
  if (!json.is_array()) throw_invalid_argument(field, kShape, json_kind(json));
  if (json.size() != 4) {
    throw_invalid_argument(field, kShape, fmt::format("an array of {} rows", json.size()));
  }
  Eigen::Matrix4d m;
  for (Eigen::Index i = 0; i < 4; ++i) {
    const nlohmann::json& row = json[static_cast<std::size_t>(i)];
    const std::string row_field = fmt::format("{}[{}]", field, i);
    if (!row.is_array()) throw_invalid_argument(row_field, "an array of 4 numbers", json_kind(row));
    if (row.size() != 4) {
      throw_invalid_argument(row_field, "an array of 4 numbers",
                             fmt::format("{} values", row.size()));
    }
    for (Eigen::Index j = 0; j < 4; ++j) {
      const nlohmann::json& value = row[static_cast<std::size_t>(j)];
      if (!value.is_number()) throw_invalid_argument(entry(field, i, j), "a number", value.dump());
      m(i, j) = value.get<double>();
    }
  }
  return from_matrix(m, field);
}

nlohmann::json RigidTransform::to_json() const {
  const Eigen::Matrix4d m = matrix();
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < 4; ++i) {
    rows.push_back(nlohmann::json::array({m(i, 0), m(i, 1), m(i, 2), m(i, 3)}));
  }
  return rows;
}

Eigen::Matrix4d RigidTransform::matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation_;
  m.topRightCorner<3, 1>() = translation_m_;
  return m;
}

RigidTransform RigidTransform::inverse() const {
  const Eigen::Matrix3d r_inverse = rotation_.transpose();
  return RigidTransform(r_inverse, -(r_inverse * translation_m_));
}

RigidTransform RigidTransform::operator*(const RigidTransform& rhs) const {
  return RigidTransform(rotation_ * rhs.rotation_, rotation_ * rhs.translation_m_ + translation_m_);
}

Eigen::Vector3d RigidTransform::apply(const Eigen::Vector3d& point_m) const {
  return rotation_ * point_m + translation_m_;
}

Eigen::Vector3d RigidTransform::rotate(const Eigen::Vector3d& vector) const {
  return rotation_ * vector;
}

Pose RigidTransform::apply(const Pose& pose) const {
  return Pose{apply(pose.position_m),
              (Eigen::Quaterniond(rotation_) * pose.orientation.normalized()).normalized()};
}

}  // namespace pnp::geometry
