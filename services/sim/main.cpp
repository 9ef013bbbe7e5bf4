// pnp-sim-server: batches of pick-and-place environments behind SimulationService.
//   --address 127.0.0.1:50051  [--metrics-address 127.0.0.1:9100]
//   [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]] [--auth-policy FILE] [--insecure]
//   (docs/RELIABILITY.md, "Who may do what")

#include <CLI/CLI.hpp>
#include <chrono>

#include "common/error.h"
#include "common/version.h"
#include "services/common/metrics_registry.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/sim/sim_service.h"

int main(int argc, char** argv) {
  using namespace pnp::services;
  catch_termination_signals();
  CLI::App app{"Serve MuJoCo pick-and-place environments", "pnp-sim-server"};
  std::string address = "127.0.0.1:50051";
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  std::string metrics_address;
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  ServerSecurityFlags security_flags;
  add_server_security_flags(app, security_flags, /*audit_db_flag=*/true);
  StreamLimitOptions limit_options;
  double idle_timeout_s = 0;
  add_stream_limit_flags(app, limit_options, idle_timeout_s);
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  try {
    ServerSecurity security = load_server_security(security_flags, address, metrics_address);
    const auto audit = open_audit_trail(security_flags.audit_db, "sim");
    security.audit = audit.get();
    MetricsRegistry metrics;
    StreamLimits limits(stream_limit_options(limit_options, idle_timeout_s), "sim");
    SimServiceImpl service(&metrics, &limits);
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 16 << 20,
                           .services = {&service},
                           .service_names = {"pnp.sim.v1.SimulationService"},
                           // Interceptors cost every call: only when someone can scrape.
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address,
                           .security = security,
                           .log_name = "sim"});
    return serve_until_terminated(
        runtime, "sim",
        [&] {
          if (const int closed = service.registry().expire(std::chrono::steady_clock::now()))
            log_event("sim", "expired", {{"batches", closed}});
        },
        std::chrono::seconds(1));
  } catch (const pnp::Error& e) {
    log_event("sim", "fatal", {{"error", e.what()}});
    return 1;
  }
}
