#include "sim/inverse_kinematics.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cstddef>
#include <vector>

#include "common/error.h"

namespace pnp::sim {

Eigen::Vector3d rotation_error(const Eigen::Matrix3d& desired, const Eigen::Matrix3d& current) {
  const Eigen::AngleAxisd aa(desired * current.transpose());
  return aa.axis() * aa.angle();
}

namespace {

Eigen::Matrix3d site_rotation(const mjData* d, int site) {
  // MuJoCo stores 3x3 matrices row-major.
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->site_xmat + 9 * site);
}

}  // namespace

IkResult solve_site_ik(const mjModel* m, mjData* d, int site, std::span<const int> joints,
                       const IkTarget& target, std::span<const double> nominal,
                       const IkOptions& options) {
  const auto n = static_cast<Eigen::Index>(joints.size());
  if (nominal.size() != joints.size()) {
    throw_internal("solve_site_ik: nominal posture size differs from the joint count");
  }
  std::vector<mjtNum> jacp(static_cast<std::size_t>(3 * m->nv));
  std::vector<mjtNum> jacr(static_cast<std::size_t>(3 * m->nv));
  Eigen::MatrixXd jac(6, n);
  IkResult result;
  for (result.iterations = 0; result.iterations < options.max_iterations; ++result.iterations) {
    mj_kinematics(m, d);
    mj_comPos(m, d);
    Eigen::Matrix<double, 6, 1> error;
    error.head<3>() = target.position - Eigen::Map<const Eigen::Vector3d>(d->site_xpos + 3 * site);
    error.tail<3>() = rotation_error(target.rotation, site_rotation(d, site));
    result.position_error_m = error.head<3>().norm();
    result.rotation_error_rad = error.tail<3>().norm();
    if (result.position_error_m < options.position_tolerance_m &&
        result.rotation_error_rad < options.rotation_tolerance_rad) {
      result.converged = true;
      break;
    }
    mj_jacSite(m, d, jacp.data(), jacr.data(), site);
    Eigen::VectorXd to_nominal(n);
    for (Eigen::Index j = 0; j < n; ++j) {
      const int dof = m->jnt_dofadr[joints[static_cast<std::size_t>(j)]];
      for (int r = 0; r < 3; ++r) {
        jac(r, j) = jacp[static_cast<std::size_t>(r * m->nv + dof)];
        jac(r + 3, j) = jacr[static_cast<std::size_t>(r * m->nv + dof)];
      }
      to_nominal(j) = nominal[static_cast<std::size_t>(j)] -
                      d->qpos[m->jnt_qposadr[joints[static_cast<std::size_t>(j)]]];
    }
    const Eigen::Matrix<double, 6, 6> jjt =
        jac * jac.transpose() + options.damping * Eigen::Matrix<double, 6, 6>::Identity();
    const Eigen::MatrixXd pinv =
        jac.transpose() * jjt.ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
    const Eigen::VectorXd nullspace =
        (Eigen::MatrixXd::Identity(n, n) - pinv * jac) * (options.nullspace_gain * to_nominal);
    const Eigen::VectorXd dq = pinv * error + nullspace;
    for (Eigen::Index j = 0; j < n; ++j) {
      const int joint = joints[static_cast<std::size_t>(j)];
      double& q = d->qpos[m->jnt_qposadr[joint]];
      q += std::clamp(dq(j), -0.2, 0.2);  // small steps keep the linearisation valid
      if (m->jnt_limited[joint]) {
        q = std::clamp(q, m->jnt_range[2 * joint], m->jnt_range[2 * joint + 1]);
      }
    }
  }
  return result;
}

}  // namespace pnp::sim
