#pragma once
// The few socket calls the platform's own poll() servers share (the /metrics endpoint and
// the dashboard's connection guard): a non-blocking listening socket on "host:port", the
// port it got, and a peer's address as the per-peer connection caps count it.

#include <sys/socket.h>

#include <string>

#include "services/common/unique_fd.h"

namespace pnp::services {

// Listening and non-blocking (accept() never blocks on a client that already left), with
// SO_REUSEADDR only: a port in use is refused. `what` names the server in errors:
// INVALID_ARGUMENT for a malformed address, UNAVAILABLE if it cannot listen.
UniqueFd listen_on(const std::string& address, const std::string& what);

int bound_port(int fd);  // 0 if unknown

// The peer's address without its port ("127.0.0.1", "::1").
std::string peer_of(const sockaddr_storage& storage);

std::string errno_text(int error);

}  // namespace pnp::services
