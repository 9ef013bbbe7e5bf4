// pnp-store-server: the one process that opens the platform's SQLite store, serving it as
// pnp.store.v1.StoreService to servers on other machines (services/store/remote_store.h).
//   --address 127.0.0.1:50050  --db FILE (or $PNP_DB; created and migrated if needed)
//   [--metrics-address 127.0.0.1:9100]
//   [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]] [--auth-policy FILE] [--insecure]

#include <CLI/CLI.hpp>
#include <chrono>
#include <string>

#include "common/error.h"
#include "common/version.h"
#include "rl/checkpoint_probe.h"
#include "services/common/address.h"
#include "services/common/metrics_registry.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/common/store_path.h"
#include "services/store/checkpoint_chunks.h"
#include "services/store/store_service.h"

int main(int argc, char** argv) {
  using namespace pnp::services;
  catch_termination_signals();
  CLI::App app{"Serve the platform's store to the other servers", "pnp-store-server"};
  std::string address = "127.0.0.1:50050";
  std::string db;
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  std::string metrics_address;
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  app.add_option("--db", db, "SQLite store [$PNP_DB]; created if it does not exist");
  ServerSecurityFlags security_flags;
  add_server_security_flags(app, security_flags);
  StreamLimitOptions limit_options;
  double idle_timeout_s = 0;
  add_stream_limit_flags(app, limit_options, idle_timeout_s);
  // What one checkpoint, one run and one principal may hold (store/store_quotas.h).
  pnp::store::StoreQuotas quotas;
  long long checkpoint_mb = quotas.max_checkpoint_bytes >> 20;
  long long run_mb = quotas.max_run_checkpoint_bytes >> 20;
  app.add_option("--max-checkpoint-mb", checkpoint_mb, "the largest checkpoint taken, in MiB")
      ->check(CLI::Range(1LL, static_cast<long long>(kMaxCheckpointBytes >> 20)))
      ->capture_default_str();
  app.add_option("--max-run-checkpoint-mb", run_mb,
                 "what all of one run's checkpoints may hold together, in MiB")
      ->check(CLI::Range(1LL, 1LL << 30))
      ->capture_default_str();
  app.add_option("--max-open-runs-per-principal", quotas.max_open_runs_per_principal,
                 "pending or running runs one authenticated principal may have created")
      ->check(CLI::Range(1, 1'000'000))
      ->capture_default_str();
  long long transfer_mb = kDefaultMaxTransferBytes >> 20;
  app.add_option("--max-transfer-mb", transfer_mb,
                 "checkpoint bytes held in memory for transfers at once, in MiB (at least twice "
                 "--max-checkpoint-mb: one principal holds at most half)")
      ->check(CLI::Range(1LL, 1LL << 20))
      ->capture_default_str();
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  quotas.max_checkpoint_bytes = checkpoint_mb << 20;
  quotas.max_run_checkpoint_bytes = run_mb << 20;
  try {
    validate_address(address, "--address");  // before the file is created
    MetricsRegistry metrics;
    ServerSecurity security = load_server_security(security_flags, address, metrics_address);
    const std::string store = resolve_store_path(db, /*must_exist=*/false);
    StreamLimits limits(stream_limit_options(limit_options, idle_timeout_s), "store");
    StoreServiceImpl service(store, pnp::rl::probe_checkpoint, &limits, {}, quotas,
                             transfer_mb << 20);
    const auto audit = open_audit_trail(store, "store");
    security.audit = audit.get();
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = kStoreMessageBytes,
                           .services = {&service},
                           .service_names = {"pnp.store.v1.StoreService"},
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address,
                           .security = security,
                           .log_name = "store"});
    // The inference replicas' WatchPromotions streams end at once (they reconnect to the
    // next store server) instead of holding the shutdown for its whole grace.
    return serve_until_terminated(
        runtime, "store", [] {}, std::chrono::seconds(1), {{"db", store}},
        [&service] { service.stop_watches(); });
  } catch (const pnp::Error& e) {
    log_event("store", "fatal", {{"error", e.what()}});
    return 1;
  }
}
