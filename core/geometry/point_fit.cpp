#include "geometry/point_fit.h"

#include <Eigen/SVD>
#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp::geometry {
namespace {

using Points = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// Refuses a set that leaves the rotation undetermined, naming the frame it was seen in.
void require_spread(const Points& centred, std::string_view field, const char* frame) {
  const double spread = centred.colwise().norm().maxCoeff();
  if (spread < kMinCalibrationSpread_m) {
    throw_invalid_argument(std::string(field) + " (" + frame + ")",
                           "points at least " + std::to_string(kMinCalibrationSpread_m) +
                               " m apart (touch points across the table)",
                           "all within " + std::to_string(spread) + " m of their centre");
  }
  // The second singular value over sqrt(n): the RMS distance off the best-fitting line.
  const Eigen::JacobiSVD<Points> svd(centred);
  const double width = svd.singularValues()(1) / std::sqrt(static_cast<double>(centred.cols()));
  if (width < kMinCalibrationWidth_m) {
    throw_invalid_argument(std::string(field) + " (" + frame + ")",
                           "points not on one line (they leave the rotation about it free)",
                           "points within " + std::to_string(width) + " m of a line");
  }
}

}  // namespace

PointFit fit_rigid_transform(std::span<const PointPair> pairs, std::string_view field) {
  if (pairs.size() < kMinCalibrationPairs) {
    throw_invalid_argument(field, "at least 3 point pairs, not on one line",
                           std::to_string(pairs.size()));
  }
  const auto n = static_cast<Eigen::Index>(pairs.size());
  Points child(3, n), parent(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const PointPair& p = pairs[static_cast<std::size_t>(i)];
    if (!p.child_m.allFinite() || !p.parent_m.allFinite()) {
      throw_invalid_argument(std::string(field) + "[" + std::to_string(i) + "]",
                             "finite coordinates", "a NaN or infinity");
    }
    child.col(i) = p.child_m;
    parent.col(i) = p.parent_m;
  }
  const Eigen::Vector3d child_centre = child.rowwise().mean();
  const Eigen::Vector3d parent_centre = parent.rowwise().mean();
  const Points a = child.colwise() - child_centre;
  const Points b = parent.colwise() - parent_centre;
  require_spread(a, field, "child frame");
  require_spread(b, field, "parent frame");
  // Kabsch: R maximises trace(R^T B A^T); the sign fix keeps it a rotation, not a mirror.
  const Eigen::Matrix3d h = a * b.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d rotation = svd.matrixV() * d * svd.matrixU().transpose();
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation;
  m.topRightCorner<3, 1>() = parent_centre - rotation * child_centre;
  PointFit fit{RigidTransform::from_matrix(m, field), {}, 0};
  double sum = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double r = (fit.parent_from_child.apply(Eigen::Vector3d(child.col(i))) -
                      Eigen::Vector3d(parent.col(i)))
                         .norm();
    fit.residuals_m.push_back(r);
    sum += r * r;
  }
  fit.rms_m = std::sqrt(sum / static_cast<double>(n));
  return fit;
}

}  // namespace pnp::geometry
