// pnp-dashboard: a live web view of the platform's runs, what it serves, and episodes of
// the served hierarchy (clients/dashboard/dashboard_server.h). Prints the port it listens
// on as stdout's first line (--address 127.0.0.1:0 picks a free one), then its URL on
// stderr; stops on SIGTERM or Ctrl-C.

#include <CLI/CLI.hpp>
#include <cstdio>

#include "clients/dashboard/dashboard_server.h"
#include "common/error.h"
#include "services/common/address.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/common/transport_security.h"

int main(int argc, char** argv) {
  using namespace pnp;
  services::catch_termination_signals();
  CLI::App app{"A live web view of the platform: runs, curves, serving, episodes", "pnp-dashboard"};
  dashboard::DashboardConfig config;
  std::string sim = "127.0.0.1:50051", inference = "127.0.0.1:50060";
  app.add_option("--address", config.address,
                 "host:port for HTTP, loopback only (port 0 picks a free one)")
      ->capture_default_str();
  app.add_option("--db", config.db, "the platform's SQLite store (read only) [$PNP_DB]")
      ->envname("PNP_DB");
  app.add_option("--sim", sim, "simulation service, for the episode viewer")
      ->envname("PNP_SIM_ADDRESS")
      ->capture_default_str();
  app.add_option("--inference", inference, "inference service")
      ->envname("PNP_INFERENCE_ADDRESS")
      ->capture_default_str();
  services::ClientTlsFiles tls;  // the services' credentials: a reader's token is enough
  services::add_client_security_flags(app, tls);
  CLI11_PARSE(app, argc, argv);
  try {
    services::validate_address(sim, "--sim");
    services::validate_address(inference, "--inference");
    config.sim = services::dial(sim, tls);
    config.inference = services::dial(inference, tls);
    const dashboard::DashboardServer server(config);
    std::printf("%d\n", server.port());
    std::fflush(stdout);
    services::log_event("dashboard", "listening",
                        {{"url", "http://127.0.0.1:" + std::to_string(server.port()) + "/"}});
    services::wait_for_termination_signal();
    return 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "pnp-dashboard: %s\n", e.what());
    return e.code() == ErrorCode::kInvalidArgument ? 2 : 1;
  }
}
