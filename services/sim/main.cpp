// pnp-sim-server: batches of pick-and-place environments behind SimulationService.
//   --address 127.0.0.1:50051

#include <CLI/CLI.hpp>
#include <chrono>

#include "common/error.h"
#include "services/common/server_runtime.h"
#include "services/sim/sim_service.h"

int main(int argc, char** argv) {
  using namespace pnp::services;
  block_termination_signals();
  CLI::App app{"Serve MuJoCo pick-and-place environments", "pnp-sim-server"};
  std::string address = "127.0.0.1:50051";
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    SimServiceImpl service;
    ServerRuntime runtime({address, 16 << 20, {&service}, {"pnp.sim.v1.SimulationService"}});
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
