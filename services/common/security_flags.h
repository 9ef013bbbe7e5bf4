#pragma once
// The command-line flags every server and client shares for transport security,
// authorization and resource limits, so each binary spells them the same way.
//   servers: --tls-cert --tls-key [--tls-client-ca] [--tls-reload-s] [--auth-policy] [--insecure]
//            [--public-metrics]
//   clients: --tls-ca [--tls-cert --tls-key] [--tls-server-name] [--token-file | $PNP_TOKEN_FILE]

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <string_view>

#include "services/common/server_runtime.h"
#include "services/common/stream_limits.h"
#include "services/common/transport_security.h"

namespace pnp::services {

struct ServerSecurityFlags {
  ServerTlsFiles tls;
  std::string auth_policy;  // JSON file (security/auth_policy.h); empty: none
  bool insecure = false;
  bool public_metrics = false;
  std::string audit_db;  // a server without a store of its own: where its audit goes
};

// --max-streams N, --stream-idle-timeout-s S (services/common/stream_limits.h).
void add_stream_limit_flags(CLI::App& app, StreamLimitOptions& options, double& idle_timeout_s);
StreamLimitOptions stream_limit_options(StreamLimitOptions options, double idle_timeout_s);

// `audit_db_flag`: also --audit-db FILE, for a server that has no --db to audit into.
void add_server_security_flags(CLI::App& app, ServerSecurityFlags& flags,
                               bool audit_db_flag = false);
// Validates the files, loads the policy and checks what `address` and `metrics_address`
// would expose (errors name the flag); the audit trail is the caller's to add
// (open_audit_trail).
ServerSecurity load_server_security(const ServerSecurityFlags& flags, const std::string& address,
                                    const std::string& metrics_address);

// The audit trail in the store at `db` (created and migrated if needed); a record that
// cannot be written is reported in `service`'s JSON log, which has every record anyway.
// Null for an empty `db`: the JSON log only.
std::unique_ptr<store::AuditTrail> open_audit_trail(const std::string& db,
                                                    std::string_view service);
// How every audit trail of `service` reports records it could not write: an
// audit_write_failed event in the JSON log.
store::AuditTrail::Report audit_failure_report(std::string_view service);

// `prefix` distinguishes a server's own outgoing connections ("sim-" for a trainer's
// simulation services: --sim-tls-ca ...); empty for a client's.
void add_client_security_flags(CLI::App& app, ClientTlsFiles& files,
                               const std::string& prefix = "");

}  // namespace pnp::services
