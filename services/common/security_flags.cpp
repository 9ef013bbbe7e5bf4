#include "services/common/security_flags.h"

#include <cctype>

namespace pnp::services {

void add_server_security_flags(CLI::App& app, ServerSecurityFlags& flags, bool audit_db_flag) {
  // Each also from the environment, so a deployment sets them once for every server.
  app.add_option("--tls-cert", flags.tls.cert, "PEM certificate chain: serve TLS")
      ->envname("PNP_SERVER_TLS_CERT");
  app.add_option("--tls-key", flags.tls.key, "PEM private key of --tls-cert")
      ->envname("PNP_SERVER_TLS_KEY");
  app.add_option("--tls-client-ca", flags.tls.client_ca,
                 "PEM CA: require client certificates it signed (mutual TLS)")
      ->envname("PNP_SERVER_TLS_CLIENT_CA");
  app.add_option("--tls-reload-s", flags.tls.reload_s,
                 "how often the TLS files are checked for changes (rotation)")
      ->capture_default_str();
  app.add_option("--auth-policy", flags.auth_policy,
                 "JSON policy: which principals (token or certificate) may call what")
      ->envname("PNP_AUTH_POLICY");
  app.add_flag("--insecure", flags.insecure,
               "allow plaintext gRPC and /metrics on a non-loopback address");
  app.add_flag("--public-metrics", flags.public_metrics,
               "allow /metrics (plaintext HTTP, read-only counters) on a non-loopback address");
  if (audit_db_flag) {
    app.add_option("--audit-db", flags.audit_db,
                   "SQLite store to append the audit trail to (created if missing; empty: the "
                   "JSON log only)");
  }
}

void add_stream_limit_flags(CLI::App& app, StreamLimitOptions& options, double& idle_timeout_s) {
  app.add_option("--max-streams", options.max_streams,
                 "streaming calls open at once; beyond, RESOURCE_EXHAUSTED")
      ->check(CLI::Range(1, 100'000))
      ->capture_default_str();
  app.add_option("--max-streams-per-principal", options.max_streams_per_principal,
                 "streaming calls one authenticated principal may hold open at once (0: a "
                 "quarter of --max-streams)")
      ->check(CLI::Range(0, 100'000))
      ->capture_default_str();
  idle_timeout_s = std::chrono::duration<double>(options.idle_timeout).count();
  app.add_option("--stream-idle-timeout-s", idle_timeout_s,
                 "a session or rollout stream with no message either way for this long is closed")
      ->check(CLI::Range(0.01, 86'400.0))
      ->capture_default_str();
}

StreamLimitOptions stream_limit_options(StreamLimitOptions options, double idle_timeout_s) {
  options.idle_timeout = std::chrono::milliseconds(static_cast<long long>(idle_timeout_s * 1000));
  return options;
}

store::AuditTrail::Report audit_failure_report(std::string_view service) {
  return [service = std::string(service)](const std::string& problem) {
    log_event(service, "audit_write_failed", {{"error", problem}});
  };
}

std::unique_ptr<store::AuditTrail> open_audit_trail(const std::string& db,
                                                    std::string_view service) {
  if (db.empty()) return nullptr;
  return std::make_unique<store::AuditTrail>(db, audit_failure_report(service));
}

ServerSecurity load_server_security(const ServerSecurityFlags& flags, const std::string& address,
                                    const std::string& metrics_address) {
  validate(flags.tls);
  ServerSecurity out;
  out.tls = flags.tls;
  out.insecure = flags.insecure;
  out.public_metrics = flags.public_metrics;
  if (!flags.auth_policy.empty())
    out.policy =
        std::make_shared<const security::AuthPolicy>(security::AuthPolicy::load(flags.auth_policy));
  check_exposure(address, metrics_address, out);
  return out;
}

void add_client_security_flags(CLI::App& app, ClientTlsFiles& files, const std::string& prefix) {
  const std::string p = "--" + prefix;
  // PNP_TLS_CA... for a client's own, PNP_SIM_TLS_CA... for a trainer's simulation client.
  std::string env = "PNP_";
  for (const char c : prefix) env += c == '-' ? '_' : static_cast<char>(std::toupper(c));
  app.add_option(p + "tls-ca", files.ca, "PEM CA that signed the servers' certificates: dial TLS")
      ->envname(env + "TLS_CA");
  app.add_option(p + "tls-cert", files.cert, "PEM client certificate (mutual TLS)")
      ->envname(env + "TLS_CERT");
  app.add_option(p + "tls-key", files.key, "PEM private key of the client certificate")
      ->envname(env + "TLS_KEY");
  app.add_option(p + "tls-server-name", files.server_name,
                 "the name to verify in the servers' certificates (default: the host dialled)");
  app.add_option(p + "token-file", files.token_file,
                 "file whose first line is a bearer token (TLS only)")
      ->envname(env + "TOKEN_FILE");
}

}  // namespace pnp::services
