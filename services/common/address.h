#pragma once
// host:port addresses as the servers listen on them and the clients dial them. gRPC takes
// a port above 65535 modulo 65536 (99999 becomes 34463: someone else's port), so every
// address a person types is checked here first.

#include <string>
#include <string_view>

namespace pnp::services {

// INVALID_ARGUMENT naming `field` unless `address` is host:port with a port in
// [0, 65535] (0: any free port, for listening) and a non-empty host. gRPC's "unix:PATH"
// addresses pass as they are.
void validate_address(std::string_view address, std::string_view field);

// Why a server could not listen on a host:port address, found by binding a socket there
// the way gRPC does (e.g. "Address already in use"); empty if such a bind now succeeds.
std::string listen_failure_reason(std::string_view address);

}  // namespace pnp::services
