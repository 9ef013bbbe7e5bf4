// pnp-sim-server: batches of pick-and-place environments behind SimulationService.
//   --address 127.0.0.1:50051  [--metrics-address 127.0.0.1:9100]

#include <CLI/CLI.hpp>
#include <chrono>

#include "common/error.h"
#include "services/common/metrics_registry.h"
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
  CLI11_PARSE(app, argc, argv);
  try {
    MetricsRegistry metrics;
    SimServiceImpl service(&metrics);
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 16 << 20,
                           .services = {&service},
                           .service_names = {"pnp.sim.v1.SimulationService"},
                           // Interceptors cost every call: only when someone can scrape.
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address});
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
