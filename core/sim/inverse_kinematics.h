#pragma once
// Damped-least-squares inverse kinematics for a site's pose, over a chosen set of hinge
// joints, with a null-space pull towards a nominal posture (the arms are redundant).
// Used to find each arm's home configuration, and to check reachability in tests.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <span>

namespace pnp::sim {

struct IkTarget {
  Eigen::Vector3d position;
  Eigen::Matrix3d rotation;  // desired site frame, world coordinates (columns = axes)
};

struct IkOptions {
  int max_iterations = 400;
  double damping = 1e-5;         // lambda^2: small, or the null-space pull biases the fix point
  double nullspace_gain = 0.05;  // pull towards the nominal posture per iteration
  double position_tolerance_m = 1e-5;
  double rotation_tolerance_rad = 1e-4;
};

struct IkResult {
  bool converged = false;
  int iterations = 0;
  double position_error_m = 0;
  double rotation_error_rad = 0;
};

// Moves d->qpos of `joints` (hinge joint ids, limits respected) so that `site` reaches
// `target`. Starts from the current d->qpos; `nominal` holds one angle per joint.
IkResult solve_site_ik(const mjModel* m, mjData* d, int site, std::span<const int> joints,
                       const IkTarget& target, std::span<const double> nominal,
                       const IkOptions& options = {});

// Rotation error as an axis-angle vector (world frame) taking `current` to `desired`.
Eigen::Vector3d rotation_error(const Eigen::Matrix3d& desired, const Eigen::Matrix3d& current);

}  // namespace pnp::sim
