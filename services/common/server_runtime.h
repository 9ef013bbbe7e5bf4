#pragma once
// What every pnp server does the same way: listen on an address (port 0 picks a free
// one), register the standard health service (overall "" and each service name) and
// server reflection, cap message sizes, log structured JSON lines, optionally record
// per-RPC Prometheus metrics and serve them over HTTP on a port of their own, and on
// SIGTERM or SIGINT stop taking new calls, let the running ones finish within a grace
// period, and exit cleanly.

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "security/auth_policy.h"
#include "services/common/metrics_http_server.h"
#include "services/common/metrics_registry.h"
#include "services/common/transport_security.h"
#include "store/audit_trail.h"

namespace pnp::services {

// Who may connect and call (docs/RELIABILITY.md, "Who may do what"). Plaintext is for
// loopback only unless `insecure`; an auth policy needs TLS (bearer tokens and principals
// mean nothing over plaintext).
struct ServerSecurity {
  ServerTlsFiles tls{};
  std::shared_ptr<const security::AuthPolicy> policy{};  // null: every caller may call
  bool insecure = false;               // allows plaintext (gRPC, /metrics) beyond loopback
  bool public_metrics = false;         // allows plaintext /metrics (read-only) beyond loopback
  store::AuditTrail* audit = nullptr;  // null: the audit goes to the JSON log only
};

// Refuses (FAILED_PRECONDITION, naming the flag) what would expose an unauthenticated
// port beyond this machine: plaintext gRPC or /metrics off loopback without `insecure`, or
// a policy without TLS. ServerRuntime checks it; a main checks it first too, before it
// starts work a refusal would waste.
void check_exposure(const std::string& address, const std::string& metrics_address,
                    const ServerSecurity& security);

// Calls one connection may have open at once (HTTP/2 SETTINGS_MAX_CONCURRENT_STREAMS);
// a server's own limit on streaming calls is StreamLimits.
inline constexpr int kMaxStreamsPerConnection = 512;

struct ServerConfig {
  std::string address = "127.0.0.1:0";
  int max_message_bytes = 4 << 20;
  std::vector<grpc::Service*> services{};
  std::vector<std::string> service_names{};  // full names, for the health service
  // Per-RPC metrics (rpc_metrics.h) when set; must outlive the runtime. The explicit
  // initialisers keep GCC 12 quiet about shorter aggregate initialisations.
  MetricsRegistry* metrics = nullptr;
  std::string metrics_address{};  // host:port for GET /metrics; empty: no endpoint
  ServerSecurity security{};
  std::string log_name{"server"};  // the "service" of its access and audit log lines
};

class ServerRuntime {
 public:
  explicit ServerRuntime(const ServerConfig& config);
  int port() const { return port_; }
  int metrics_port() const { return metrics_http_ ? metrics_http_->port() : 0; }  // 0: off
  grpc::Server& server() { return *server_; }
  void set_serving(bool serving);
  // Stops accepting calls and waits up to `grace` for running ones (then cancels them).
  void shutdown(std::chrono::milliseconds grace);

 private:
  std::unique_ptr<MetricsHttpServer> metrics_http_;
  std::unique_ptr<grpc::Server> server_;
  std::vector<std::string> names_;
  int port_ = 0;
};

// Call first in main: from then on SIGTERM and SIGINT, whichever thread they land on, are
// handed to wait_for_termination_signal() instead of ending the process.
void catch_termination_signals();
int wait_for_termination_signal();  // blocks until one arrives; the signal number

// Announces the port (stdout's first line, for scripts that started the server on port 0,
// and the log's "listening" event, with "metrics_port" when metrics are served),
// runs `periodic` every `period` on a background thread until SIGTERM or SIGINT, then
// drains the server (5 s grace) and returns 0.
// `draining` (if set) runs once a signal has come, before the running calls are given
// their grace: a service ends its long-lived streams there so shutdown need not wait.
int serve_until_terminated(ServerRuntime& runtime, std::string_view service,
                           const std::function<void()>& periodic, std::chrono::milliseconds period,
                           const nlohmann::json& fields = nlohmann::json::object(),
                           const std::function<void()>& draining = {});

// One JSON object per line on stderr: {"ts_ms", "service", "event", ...fields}.
void log_event(std::string_view service, std::string_view event,
               const nlohmann::json& fields = nlohmann::json::object());

}  // namespace pnp::services
