#pragma once
// What a caller may do, in five classes an authorization policy grants (docs/RELIABILITY.md,
// "Who may do what"): read state, act as a policy's agent (predict, step a simulation),
// operate the platform (train, promote, clear an E-stop), move the robot, and, for the
// platform's own servers, write the store (pnp-store-server) on an operator's behalf.

#include <optional>
#include <string_view>

namespace pnp::security {

enum class AccessClass { kReader, kAgent, kOperator, kRobot, kService };

inline constexpr AccessClass kAllAccessClasses[] = {AccessClass::kReader, AccessClass::kAgent,
                                                    AccessClass::kOperator, AccessClass::kRobot,
                                                    AccessClass::kService};

std::string_view access_class_name(
    AccessClass c);  // "reader", "agent", "operator", "robot", "service"
std::optional<AccessClass> parse_access_class(std::string_view name);

// What an RPC requires: one class, or (Stop, E-stop) any authenticated caller.
struct RpcRequirement {
  std::optional<AccessClass> access_class;  // empty: any authenticated principal
};

}  // namespace pnp::security
