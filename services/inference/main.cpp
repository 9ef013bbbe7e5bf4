// pnp-inference-server: serves the promoted hierarchy from the store (PolicyService).
//   --address 127.0.0.1:50060  --db ./pnp.db (or $PNP_DB)  --reload-ms 500
//   [--metrics-address 127.0.0.1:9101]

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdlib>

#include "common/error.h"
#include "services/common/metrics_registry.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"

int main(int argc, char** argv) {
  using namespace pnp::services;
  catch_termination_signals();
  CLI::App app{"Serve the promoted pick-and-place hierarchy", "pnp-inference-server"};
  std::string address = "127.0.0.1:50060";
  std::string db = std::getenv("PNP_DB") ? std::getenv("PNP_DB") : "pnp.db";
  int reload_ms = 500;
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  std::string metrics_address;
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  app.add_option("--db", db, "SQLite store (also $PNP_DB)")->capture_default_str();
  app.add_option("--reload-ms", reload_ms, "how often to look for newly promoted checkpoints")
      ->check(CLI::Range(10, 60'000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    MetricsRegistry metrics;
    PolicyServiceImpl service(db);
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 4 << 20,
                           .services = {&service},
                           .service_names = {"pnp.policy.v1.PolicyService"},
                           // Interceptors cost every call: only when someone can scrape.
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address});
    std::array<Gauge*, 3> batched_requests{}, batches{};
    for (std::size_t k = 0; k < 3; ++k) {
      const Labels expert{
          {"expert", std::string(pnp::sim::subtask_name(pnp::sim::kAllSubtasks[k]))}};
      batched_requests[k] =
          &metrics.gauge("pnp_inference_expert_requests",
                         "expert forward passes requested (served hierarchy)", expert);
      batches[k] = &metrics.gauge("pnp_inference_expert_batches",
                                  "batched expert forward passes run (served hierarchy)", expert);
    }
    return serve_until_terminated(
        runtime, "inference",
        [&] {
          const auto stats = service.batch_stats();
          for (std::size_t k = 0; k < 3; ++k) {
            batched_requests[k]->set(static_cast<double>(stats[k].requests));
            batches[k]->set(static_cast<double>(stats[k].batches));
          }
          try {
            if (service.reload()) log_event("inference", "reloaded");
          } catch (const pnp::Error& e) {
            if (e.code() != pnp::ErrorCode::kFailedPrecondition)
              log_event("inference", "reload_failed", {{"error", e.what()}});
          }
        },
        std::chrono::milliseconds(reload_ms), {{"db", db}, {"ready", service.ready()}});
  } catch (const pnp::Error& e) {
    log_event("inference", "fatal", {{"error", e.what()}});
    return 1;
  }
}
