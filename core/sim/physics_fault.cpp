#include "sim/physics_fault.h"

#include <algorithm>
#include <cmath>

#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

bool all_finite(const mjtNum* values, int n) {
  return std::all_of(values, values + n, [](mjtNum v) { return std::isfinite(v); });
}

}  // namespace

PhysicsFault detect_physics_fault(const mjModel* m, const mjData* d, const WorldIds& ids) {
  if (d->warning[mjWARN_BADQPOS].number > 0 || d->warning[mjWARN_BADQVEL].number > 0 ||
      d->warning[mjWARN_BADQACC].number > 0) {
    return PhysicsFault::kUnstable;
  }
  if (!all_finite(d->qpos, m->nq) || !all_finite(d->qvel, m->nv)) return PhysicsFault::kNonFinite;
  if (d->warning[mjWARN_CONTACTFULL].number > 0 || d->warning[mjWARN_CNSTRFULL].number > 0) {
    return PhysicsFault::kCapacity;
  }
  const mjtNum* v = d->qvel + ids.object_dof;  // free joint: linear then angular
  const mjtNum* p = d->qpos + ids.object_qpos;
  const double speed_sq = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const double spin_sq = v[3] * v[3] + v[4] * v[4] + v[5] * v[5];
  const double dx = p[0] - layout::kTableCenter_x, dy = p[1] - layout::kTableCenter_y,
               dz = p[2] - layout::kTableTop_z;
  constexpr double kMaxDistance = layout::kMaxObjectDistanceFromTable_m;
  if (speed_sq > layout::kMaxObjectSpeed_mps * layout::kMaxObjectSpeed_mps ||
      spin_sq > layout::kMaxObjectSpin_radps * layout::kMaxObjectSpin_radps ||
      dx * dx + dy * dy + dz * dz > kMaxDistance * kMaxDistance) {
    return PhysicsFault::kEjected;
  }
  return PhysicsFault::kNone;
}

}  // namespace pnp::sim
