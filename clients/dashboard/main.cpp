// pnp-dashboard: a live web view of the platform's runs, what it serves, and episodes of
// the served hierarchy (clients/dashboard/dashboard_server.h). Prints the port it listens
// on as stdout's first line (--address 127.0.0.1:0 picks a free one), then its URL on
// stderr; stops on SIGTERM or Ctrl-C.

#include <CLI/CLI.hpp>
#include <cstdio>

#include "clients/dashboard/dashboard_server.h"
#include "common/error.h"
#include "common/version.h"
#include "security/auth_policy.h"
#include "services/common/address.h"
#include "services/common/endpoints_file.h"
#include "services/common/replica_channel.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/common/transport_security.h"
#include "services/store/remote_store.h"
#include "services/store/store_flags.h"

int main(int argc, char** argv) {
  using namespace pnp;
  services::catch_termination_signals();
  CLI::App app{"A live web view of the platform: runs, curves, serving, episodes", "pnp-dashboard"};
  dashboard::DashboardConfig config;
  std::string sim = "127.0.0.1:50051", inference = "127.0.0.1:50060";
  app.add_option("--address", config.address,
                 "host:port to listen on (port 0 picks a free one); beyond loopback only "
                 "with --tls-cert and --tls-key")
      ->capture_default_str();
  std::string auth_policy;
  app.add_option("--tls-cert", config.tls_cert, "PEM certificate chain: serve HTTPS")
      ->envname("PNP_SERVER_TLS_CERT");
  app.add_option("--tls-key", config.tls_key, "PEM private key of --tls-cert")
      ->envname("PNP_SERVER_TLS_KEY");
  app.add_option("--auth-policy", auth_policy,
                 "the platform's authorization policy: readers only (needs TLS)")
      ->envname("PNP_AUTH_POLICY");
  auto* db_option =
      app.add_option("--db", config.db, "the platform's SQLite store (read only) [$PNP_DB]")
          ->envname("PNP_DB");
  services::RemoteStoreFlags store_flags;
  services::add_remote_store_flags(app, store_flags, db_option);
  app.add_option("--sim", sim, "simulation service, for the episode viewer")
      ->envname("PNP_SIM_ADDRESS")
      ->capture_default_str();
  app.add_option("--inference", inference, "inference service")
      ->envname("PNP_INFERENCE_ADDRESS")
      ->capture_default_str();
  std::string endpoints_file;
  services::add_endpoints_file_option(app, endpoints_file);
  // The services' credentials: --platform-tls-ca, --platform-token-file, ... (the
  // episode viewer steps a simulation and asks for actions: an agent's token).
  services::ClientTlsFiles tls;
  services::add_client_security_flags(app, tls, "platform-");
  // The front door's limits (connection_guard.h).
  double deadline_s = std::chrono::duration<double>(config.guard.answer_deadline).count();
  app.add_option("--max-connections", config.guard.max_connections,
                 "connections open at once; beyond, closed unanswered")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app.add_option("--max-connections-per-peer", config.guard.max_per_peer,
                 "connections one client address may hold")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app.add_option("--request-deadline-s", deadline_s,
                 "from a request's first byte to its answer; a client that never finishes its "
                 "request is closed then")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  config.guard.answer_deadline =
      std::chrono::milliseconds(static_cast<long long>(deadline_s * 1000));
  try {
    services::validate_address(config.address, "--address");  // before the store is opened
    const services::FileAddress from_file[] = {{"sim", "--sim", &sim},
                                               {"inference", "--inference", &inference}};
    services::apply_endpoints_file(app, endpoints_file, from_file);
    services::validate_address(sim, "--sim");
    services::validate_address(inference, "--inference");
    if (!auth_policy.empty())
      config.policy =
          std::make_shared<const security::AuthPolicy>(security::AuthPolicy::load(auth_policy));
    if (store_flags.remote())
      config.open_store = services::remote_store_opener(store_flags.address, store_flags.tls);
    config.sim = services::dial(sim, tls);
    grpc::ChannelArguments replicas;
    services::balance_over_replicas(replicas);
    config.inference = services::dial(inference, tls, replicas);
    const dashboard::DashboardServer server(config);
    std::printf("%d\n", server.port());
    std::fflush(stdout);
    const auto colon = config.address.rfind(':');
    services::log_event(
        "dashboard", "listening",
        {{"url", std::string(config.tls_cert.empty() ? "http" : "https") + "://" +
                     config.address.substr(0, colon) + ":" + std::to_string(server.port()) + "/"},
         {"readers_only", config.policy != nullptr}});
    services::wait_for_termination_signal();
    return 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "pnp-dashboard: %s\n", e.what());
    return e.code() == ErrorCode::kInvalidArgument ? 2 : 1;
  }
}
