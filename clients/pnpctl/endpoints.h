#pragma once
// Where each service listens, and how to reach it: plaintext, TLS or mutual TLS, with or
// without a bearer token (--tls-ca, --tls-cert, --tls-key, --token-file). Every client
// finds the platform the same way (pnpctl, the Python package, the examples): a flag, then
// its environment variable (PNP_SIM_ADDRESS, ...), then an endpoints file (--endpoints or
// PNP_ENDPOINTS; else runs/platform/endpoints.json when it exists: scripts/run writes it
// while the platform runs), then the conventional loopback ports (deploy/ uses the same).

#include <grpcpp/grpcpp.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <string_view>

#include "services/common/transport_security.h"

namespace pnp::pnpctl {

struct Endpoints {
  std::string sim = "127.0.0.1:50051";
  std::string approach = "127.0.0.1:50052";
  std::string manipulate = "127.0.0.1:50053";
  std::string retract = "127.0.0.1:50054";
  std::string hlc = "127.0.0.1:50055";
  std::string e2e = "127.0.0.1:50056";
  std::string inference = "127.0.0.1:50060";
  std::string robot_controller = "127.0.0.1:50070";  // not in kAllServices: not the platform's
  std::string store = "127.0.0.1:50050";  // pnp-store-server; not in kAllServices: optional
  services::ClientTlsFiles tls;           // the same for every service
  // The endpoints file the addresses not given by flag or environment came from; empty:
  // none (the defaults). Named in an UNAVAILABLE error: the file may be stale.
  std::string endpoints_file;

  // A channel to `address` with the credentials above (INVALID_ARGUMENT naming the flag
  // for a bad address or file).
  std::shared_ptr<grpc::Channel> channel(const std::string& address) const;

  // The flag an address came from ("--sim", ...; "address" for one that is none of them).
  std::string_view flag_of(const std::string& address) const;

  // The training service of a role; INVALID_ARGUMENT for an unknown role.
  const std::string& training(const std::string& role) const;
  // Any service by name: sim, inference, store, robot (the arm's controller), or a role.
  // INVALID_ARGUMENT naming --only otherwise.
  const std::string& address_of(const std::string& service) const;
};

inline constexpr const char* kAllServices[] = {"sim", "approach", "manipulate", "retract",
                                               "hlc", "e2e",      "inference"};

void add_endpoint_options(CLI::App& app, Endpoints& endpoints);

// After parsing: the endpoints file's addresses for every service whose flag and variable
// were not given. INVALID_ARGUMENT naming the file and the key for a file that is not a
// JSON object of known names to addresses (or NOT_FOUND for a named file that is missing).
void apply_endpoints_file(const CLI::App& app, Endpoints& endpoints);

// `message`, with a hint when the addresses came from an endpoints file that may be stale.
std::string with_endpoints_hint(const Endpoints& endpoints, const std::string& message);

}  // namespace pnp::pnpctl
