#pragma once
// Conversions between the protos of pnp.common.v1 and the core's types. Everything that
// comes from a client is validated here, at the boundary: wrong sizes, non-finite values
// and unspecified or unknown enum values are INVALID_ARGUMENT naming the field.

#include <string>
#include <string_view>

#include "common/wall_breakdown.h"
#include "pnp/common/v1/common.pb.h"
#include "sim/actuation.h"
#include "sim/object_shape.h"
#include "sim/observation.h"
#include "sim/robot.h"
#include "sim/subtask.h"
#include "sim/world_profile.h"

namespace pnp::services {

sim::Robot from_proto(common::v1::Robot robot, std::string_view field);
sim::ObjectShape from_proto(common::v1::ObjectShape object, std::string_view field);
// WORLD_UNSPECIFIED is the default world (gym); unknown values are INVALID_ARGUMENT.
sim::WorldProfile from_proto(common::v1::World world, std::string_view field);
// ACTUATION_UNSPECIFIED is the robot's default; unknown values, and an actuation the robot
// does not have, are INVALID_ARGUMENT.
sim::Actuation from_proto(common::v1::Actuation actuation, sim::Robot robot,
                          std::string_view field);
common::v1::Actuation to_proto(sim::Actuation actuation);
common::v1::Robot to_proto(sim::Robot robot);
common::v1::World to_proto(sim::WorldProfile world);
common::v1::ObjectShape to_proto(sim::ObjectShape object);
common::v1::Subtask to_proto(sim::Subtask subtask);
// A subtask as an index (sim::Subtask's value: 0 approach, 1 manipulate, 2 retract), -1
// for none (an end-to-end policy, or unspecified): what the episode view colours by.
int subtask_index(common::v1::Subtask subtask);

// Role names as the store keeps them ("approach", ..., "hlc", "e2e").
std::string role_name(common::v1::Role role, std::string_view field);
common::v1::Role role_from_name(std::string_view name);

sim::Observation from_proto(const common::v1::Observation& o, std::string_view field);
sim::Goal from_proto(const common::v1::Vector3& v, std::string_view field);
void to_proto(const sim::Observation& o, common::v1::Observation& out);
void to_proto(const Eigen::Vector3d& v, common::v1::Vector3& out);
void to_proto(const sim::Action& a, common::v1::Action& out);

// As given: the store validates each phase (store::Store::add_wall_time); total_s is the
// phases' sum, never read from a message.
void to_proto(const WallBreakdown& wall, common::v1::WallBreakdown& out);
WallBreakdown from_proto(const common::v1::WallBreakdown& wall);

}  // namespace pnp::services
