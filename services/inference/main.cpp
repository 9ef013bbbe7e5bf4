// pnp-inference-server: serves the promoted policy from the store (PolicyService): the
// hierarchy (choreographer + experts) or, with --policy e2e, the end-to-end baseline.
//   --address 127.0.0.1:50060  --db FILE (or $PNP_DB; an existing store unless --create-db)
//   --reload-ms 500 (how often --db is read for new promotions)
//   or --store host:port (pnp-store-server, whose WatchPromotions stream says when to reload;
//   [--store-tls-ca FILE ...])
//   --policy hierarchy|e2e  [--metrics-address 127.0.0.1:9101]
//   [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]] [--auth-policy FILE] [--insecure]
//   (docs/RELIABILITY.md, "Who may do what"; operator calls are audited into --db)

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdlib>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/version.h"
#include "nn/gemm_path.h"
#include "services/common/metrics_registry.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/common/store_path.h"
#include "services/inference/policy_service.h"
#include "services/inference/promotion_watcher.h"
#include "services/store/remote_audit.h"
#include "services/store/remote_store.h"
#include "services/store/store_flags.h"

int main(int argc, char** argv) {
  using namespace pnp::services;
  catch_termination_signals();
  CLI::App app{"Serve the promoted pick-and-place policy", "pnp-inference-server"};
  std::string address = "127.0.0.1:50060";
  std::string db;
  bool create_db = false;
  int reload_ms = 500;
  std::string policy = "hierarchy";
  app.add_option("--address", address, "host:port to listen on (port 0: any free port)")
      ->capture_default_str();
  std::string metrics_address;
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  auto* db_option =
      app.add_option("--db", db, "SQLite store [$PNP_DB]; it must exist unless --create-db");
  RemoteStoreFlags store_flags;
  add_remote_store_flags(app, store_flags, db_option);
  app.add_flag("--create-db", create_db, "start on an empty store if --db does not exist");
  app.add_option("--reload-ms", reload_ms, "how often to look for newly promoted checkpoints")
      ->check(CLI::Range(10, 60'000))
      ->capture_default_str();
  app.add_option("--policy", policy,
                 "what to serve: the promoted hierarchy, or the promoted end-to-end (e2e) "
                 "DDPG+HER baseline")
      ->check(CLI::IsMember({"hierarchy", "e2e"}))
      ->capture_default_str();
  ServerSecurityFlags security_flags;
  add_server_security_flags(app, security_flags);
  StreamLimitOptions limit_options;
  double idle_timeout_s = 0;
  add_stream_limit_flags(app, limit_options, idle_timeout_s);
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  try {
    // Refuses a bad PNP_GEMM before serving; the path is logged with "listening".
    const std::string gemm_path(pnp::nn::gemm_path_name(pnp::nn::active_gemm_path()));
    MetricsRegistry metrics;
    const auto kind = pnp::serving::parse_policy_kind(policy, "--policy");
    ServerSecurity security = load_server_security(security_flags, address, metrics_address);
    const bool remote = !store_flags.address.empty();
    const std::string store = remote ? "" : resolve_store_path(db, !create_db);
    StreamLimits limits(stream_limit_options(limit_options, idle_timeout_s), "inference");
    MetricsRegistry* const served_metrics = metrics_address.empty() ? nullptr : &metrics;
    const auto service =
        remote ? std::make_unique<PolicyServiceImpl>(
                     remote_store_opener(store_flags.address, store_flags.tls), kind, &limits,
                     served_metrics)
               : std::make_unique<PolicyServiceImpl>(store, kind, &limits, served_metrics);
    // The trail is a table of the store: in the file, or through the store server.
    const auto audit =
        remote ? open_remote_audit_trail(store_flags.address, store_flags.tls, "inference")
               : open_audit_trail(store, "inference");
    security.audit = audit.get();
    const auto reload = [&service] {
      try {
        if (service->reload()) log_event("inference", "reloaded");
      } catch (const pnp::Error& e) {
        if (e.code() != pnp::ErrorCode::kFailedPrecondition)
          log_event("inference", "reload_failed", {{"error", e.what()}});
      } catch (const std::exception& e) {  // keeps serving the current policy
        log_event("inference", "reload_failed", {{"error", e.what()}});
      }
    };
    std::optional<PromotionWatcher> watcher;
    if (remote) {
      auto watch_store = std::make_unique<RemoteStore>(
          dial(store_flags.address, store_flags.tls, store_channel_arguments()),
          store_flags.address);
      watcher.emplace(std::move(watch_store), reload, [](const std::string& message) {
        log_event("inference", "store_watch", {{"message", message}});
      });
    }
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 4 << 20,
                           .services = {service.get()},
                           .service_names = {"pnp.policy.v1.PolicyService"},
                           // Interceptors cost every call: only when someone can scrape.
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address,
                           .security = security,
                           .log_name = "inference"});
    // One pair per batched actor: the three experts, or the e2e actor.
    std::vector<Gauge*> batched_requests, batches;
    for (const std::string& actor : pnp::serving::batched_actors(kind)) {
      const Labels expert{{"expert", actor}};
      batched_requests.push_back(&metrics.gauge("pnp_inference_expert_requests",
                                                "actor forward passes requested (served policy)",
                                                expert));
      batches.push_back(&metrics.gauge("pnp_inference_expert_batches",
                                       "batched actor forward passes run (served policy)", expert));
    }
    return serve_until_terminated(
        runtime, "inference",
        [&] {
          const auto stats = service->batch_stats();
          for (std::size_t k = 0; k < stats.size() && k < batches.size(); ++k) {
            batched_requests[k]->Set(static_cast<double>(stats[k].requests));
            batches[k]->Set(static_cast<double>(stats[k].batches));
          }
          if (!remote) reload();  // a remote store's promotions come by its watcher
        },
        std::chrono::milliseconds(reload_ms),
        {{"db", db},
         {"store", store_flags.address},
         {"policy", policy},
         {"ready", service->ready()},
         {"gemm_path", gemm_path}});
  } catch (const pnp::Error& e) {
    log_event("inference", "fatal", {{"error", e.what()}});
    return 1;
  }
}
