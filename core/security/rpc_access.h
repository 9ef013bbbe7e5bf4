#pragma once
// The one table of what every RPC of every pnp service requires once an authorization
// policy is configured, keyed by the gRPC method path ("/package.Service/Method"). An RPC
// missing here is denied to everyone (and a test fails), never allowed by omission.

#include <optional>
#include <span>
#include <string_view>

#include "security/access_class.h"

namespace pnp::security {

struct RpcAccess {
  std::string_view path;
  RpcRequirement requirement;
  bool audited;  // operator and robot calls, and every Stop: appended to the audit trail
};

std::span<const RpcAccess> rpc_access_table();
const RpcAccess* find_rpc_access(std::string_view path);  // nullptr: not in the table

}  // namespace pnp::security
