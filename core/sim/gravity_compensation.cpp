#include "sim/gravity_compensation.h"

#include <cstddef>

namespace pnp::sim {

GravityCompensation::GravityCompensation(const mjModel* m, int arm_root_body)
    : root_body_(arm_root_body),
      subtree_mass_(m->body_subtreemass[arm_root_body]),
      jacobian_(static_cast<std::size_t>(3 * m->nv)) {}

void GravityCompensation::apply(const mjModel* m, mjData* d) {
  mj_jacSubtreeCom(m, d, jacobian_.data(), root_body_);
  const mjtNum* g = m->opt.gravity;
  for (int dof = 0; dof < m->nv; ++dof) {
    mjtNum torque = 0;
    for (int k = 0; k < 3; ++k)
      torque -= jacobian_[static_cast<std::size_t>(k * m->nv + dof)] * g[k];
    // Only the arm's dofs have a non-zero Jacobian column; the object's stay untouched.
    d->qfrc_applied[dof] = torque * subtree_mass_;
  }
}

}  // namespace pnp::sim
