#pragma once
// Whether a pick-and-place world's physics has failed: a MuJoCo bad-state warning, a
// non-finite state, a full contact or constraint buffer, or an object moving in a way no
// contact could make it (world_layout.h's plausibility limits: a contact that blew up
// without producing a NaN). One check for every world that steps this model: the mocap
// environment after each substep, the simulated arm after each control tick.

#include <mujoco/mujoco.h>

#include "sim/environment.h"
#include "sim/world_model.h"

namespace pnp::sim {

PhysicsFault detect_physics_fault(const mjModel* m, const mjData* d, const WorldIds& ids);

}  // namespace pnp::sim
