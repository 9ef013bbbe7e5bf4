#pragma once
// The command-line flags every server and client shares for transport security and
// authorization, so each binary spells them the same way.
//   servers: --tls-cert --tls-key [--tls-client-ca] [--tls-reload-s] [--auth-policy] [--insecure]
//   clients: --tls-ca [--tls-cert --tls-key] [--tls-server-name] [--token-file | $PNP_TOKEN_FILE]

#include <CLI/CLI.hpp>
#include <string>

#include "services/common/server_runtime.h"
#include "services/common/transport_security.h"

namespace pnp::services {

struct ServerSecurityFlags {
  ServerTlsFiles tls;
  std::string auth_policy;  // JSON file (security/auth_policy.h); empty: none
  bool insecure = false;
};

void add_server_security_flags(CLI::App& app, ServerSecurityFlags& flags);
// Validates the files and loads the policy (errors name the flag); the audit trail is the
// caller's to add.
ServerSecurity load_server_security(const ServerSecurityFlags& flags);

// `prefix` distinguishes a server's own outgoing connections ("sim-" for a trainer's
// simulation services: --sim-tls-ca ...); empty for a client's.
void add_client_security_flags(CLI::App& app, ClientTlsFiles& files,
                               const std::string& prefix = "");

}  // namespace pnp::services
