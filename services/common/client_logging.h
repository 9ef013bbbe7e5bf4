#pragma once
// A command-line client's stderr carries its own errors, which say what failed and what to
// do; gRPC's internal lines ("E1206 ... ssl_transport_security.cc ... Handshake failed")
// came before them and read as a second, cryptic failure. Clients drop them unless the user
// asks for gRPC's own logging with GRPC_VERBOSITY (then they are printed as gRPC prints them).

namespace pnp::services {

// Call once at the start of main, before any channel.
void quiet_grpc_logs_unless_asked();

}  // namespace pnp::services
