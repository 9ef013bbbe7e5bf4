#include "services/common/sim_convert.h"

#include <algorithm>
#include <array>
#include <string>
#include <utility>

#include "common/error.h"

namespace pnp::services {
namespace {

namespace sv1 = pnp::sim::v1;

constexpr std::array<std::pair<sim::Objective, sv1::Objective>, 4> kObjectives{{
    {sim::Objective::kApproach, sv1::OBJECTIVE_APPROACH},
    {sim::Objective::kManipulate, sv1::OBJECTIVE_MANIPULATE},
    {sim::Objective::kRetract, sv1::OBJECTIVE_RETRACT},
    {sim::Objective::kTask, sv1::OBJECTIVE_TASK},
}};

constexpr std::array<std::pair<sim::PhysicsFault, sv1::PhysicsFault>, 5> kFaults{{
    {sim::PhysicsFault::kNone, sv1::PHYSICS_FAULT_NONE},
    {sim::PhysicsFault::kUnstable, sv1::PHYSICS_FAULT_UNSTABLE},
    {sim::PhysicsFault::kNonFinite, sv1::PHYSICS_FAULT_NON_FINITE},
    {sim::PhysicsFault::kCapacity, sv1::PHYSICS_FAULT_CAPACITY},
    {sim::PhysicsFault::kEjected, sv1::PHYSICS_FAULT_EJECTED},
}};

template <typename Core, typename Proto, std::size_t N>
Core core_value(const std::array<std::pair<Core, Proto>, N>& table, Proto value,
                std::string_view field, std::string_view expected) {
  const auto it = std::find_if(table.begin(), table.end(),
                               [&](const auto& entry) { return entry.second == value; });
  if (it == table.end()) throw_invalid_argument(field, expected, std::to_string(value));
  return it->first;
}

template <typename Core, typename Proto, std::size_t N>
Proto proto_value(const std::array<std::pair<Core, Proto>, N>& table, Core value) {
  const auto it = std::find_if(table.begin(), table.end(),
                               [&](const auto& entry) { return entry.first == value; });
  if (it == table.end()) throw Error(ErrorCode::kInternal, "a core enum value with no proto value");
  return it->second;
}

}  // namespace

sim::Objective from_proto(sv1::Objective objective, std::string_view field) {
  return core_value(kObjectives, objective, field,
                    "one of OBJECTIVE_APPROACH, _MANIPULATE, _RETRACT, _TASK");
}

sv1::Objective to_proto(sim::Objective objective) {
  return proto_value(kObjectives, objective);
}

sim::PhysicsFault from_proto(sv1::PhysicsFault fault, std::string_view field) {
  return core_value(kFaults, fault, field,
                    "one of PHYSICS_FAULT_NONE, _UNSTABLE, _NON_FINITE, _CAPACITY, _EJECTED");
}

sv1::PhysicsFault to_proto(sim::PhysicsFault fault) {
  return proto_value(kFaults, fault);
}

}  // namespace pnp::services
