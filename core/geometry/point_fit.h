#pragma once
// Calibration from touched points: the rigid transform that best maps points measured in
// one frame (the simulation's table points) onto the same points measured in another (the
// arm's base frame, read from O_T_EE with the fingertips on each point). Least squares
// over rotation and translation, no scale (Kabsch; Umeyama's reflection correction), so a
// mismeasured point shows as a residual, never as a skewed transform.

#include <Eigen/Core>
#include <span>
#include <string_view>
#include <vector>

#include "geometry/rigid_transform.h"

namespace pnp::geometry {

struct PointPair {
  Eigen::Vector3d child_m;   // the point in the frame being calibrated (e.g. the simulation)
  Eigen::Vector3d parent_m;  // the same point measured in the reference frame (the base)
};

struct PointFit {
  RigidTransform parent_from_child;
  std::vector<double> residuals_m;  // per pair: |T child - parent|
  double rms_m = 0;
};

// Fewest pairs, and how spread they must be, for the rotation to be determined.
inline constexpr std::size_t kMinCalibrationPairs = 3;
inline constexpr double kMinCalibrationSpread_m = 0.05;  // from their centroid, the farthest
inline constexpr double kMinCalibrationWidth_m = 0.01;   // off their best line (collinear)

// INVALID_ARGUMENT naming `field` (or `field[i]`): fewer than 3 pairs, a non-finite
// coordinate, points within kMinCalibrationSpread_m of each other, or points on one line
// (they leave the rotation about it free) in either frame.
PointFit fit_rigid_transform(std::span<const PointPair> pairs, std::string_view field);

}  // namespace pnp::geometry
