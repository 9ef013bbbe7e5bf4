#pragma once
// Conversions between the enums of pnp.sim.v1 and the core's, both ways, from one table
// each: the simulation service and its remote clients cannot disagree.

#include <string_view>

#include "pnp/sim/v1/sim_service.pb.h"
#include "sim/environment.h"
#include "sim/subtask.h"

namespace pnp::services {

// INVALID_ARGUMENT naming `field` for OBJECTIVE_UNSPECIFIED or an unknown value.
sim::Objective from_proto(pnp::sim::v1::Objective objective, std::string_view field);
pnp::sim::v1::Objective to_proto(sim::Objective objective);

// INVALID_ARGUMENT naming `field` for PHYSICS_FAULT_UNSPECIFIED or an unknown value.
sim::PhysicsFault from_proto(pnp::sim::v1::PhysicsFault fault, std::string_view field);
pnp::sim::v1::PhysicsFault to_proto(sim::PhysicsFault fault);

}  // namespace pnp::services
