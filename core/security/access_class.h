#pragma once
// What a caller may do, in six classes an authorization policy grants (docs/RELIABILITY.md,
// "Who may do what"): read state, act as a policy's agent (predict, step a simulation),
// operate the platform (train, promote, clear an E-stop), move the robot; and, for the
// platform's own servers, write the store (pnp-store-server) under their own name, and
// carry out in the store an operator call the server authenticated itself (pnp-inference's
// PromoteCheckpoint), recorded as that operator acting through the server.

#include <optional>
#include <string_view>

namespace pnp::security {

enum class AccessClass { kReader, kAgent, kOperator, kRobot, kService, kDelegate };

inline constexpr AccessClass kAllAccessClasses[] = {AccessClass::kReader,   AccessClass::kAgent,
                                                    AccessClass::kOperator, AccessClass::kRobot,
                                                    AccessClass::kService,  AccessClass::kDelegate};

std::string_view access_class_name(
    AccessClass c);  // "reader", "agent", "operator", "robot", "service", "delegate"
std::optional<AccessClass> parse_access_class(std::string_view name);

// What an RPC requires: one class, either of two (an operator, or a server acting for one
// it authenticated), or (Stop, E-stop) any authenticated caller.
struct RpcRequirement {
  std::optional<AccessClass> access_class;  // empty: any authenticated principal
  std::optional<AccessClass> or_class{};    // set: this class is enough too
};

}  // namespace pnp::security
