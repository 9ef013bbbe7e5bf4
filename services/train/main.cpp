// pnp-train-server: trains one role (TrainingService) in the background, writing runs,
// learning curves and checkpoints to the store; resumes interrupted runs at start.
//   --role approach  --address 127.0.0.1:50052  --db FILE (or $PNP_DB; created if missing)
//   or --store host:port (pnp-store-server; [--store-tls-ca FILE ...])
//   --threads 0
//   [--metrics-address 127.0.0.1:9102]  [--sim-address host:port]...  (rollouts on remote
//   simulation services, round robin; default: in this process)
//   [--tls-cert FILE --tls-key FILE [--tls-client-ca FILE]] [--auth-policy FILE] [--insecure]
//   [--sim-tls-ca FILE [--sim-tls-cert FILE --sim-tls-key FILE] [--sim-token-file FILE]]
//   (docs/RELIABILITY.md, "Who may do what"; operator calls are audited into --db)

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "build_info.h"
#include "clients/sim_client/remote_env_factory.h"
#include "clients/sim_client/sim_target.h"
#include "common/error.h"
#include "common/version.h"
#include "nn/gemm_path.h"
#include "services/common/metrics_registry.h"
#include "services/common/security_flags.h"
#include "services/common/server_runtime.h"
#include "services/common/store_path.h"
#include "services/store/remote_audit.h"
#include "services/store/remote_store.h"
#include "services/store/store_flags.h"
#include "services/train/training_service.h"

namespace {

// Training progress for Prometheus, refreshed once a second from the run manager.
class TrainingGauges {
 public:
  TrainingGauges(pnp::services::MetricsRegistry& metrics, const std::string& role)
      : queued_(
            metrics.gauge("pnp_training_queued_runs", "Runs waiting to train", {{"role", role}})),
        active_(metrics.gauge("pnp_training_active_run_id", "Id of the run training now (0: idle)",
                              {{"role", role}})),
        steps_(metrics.gauge("pnp_training_env_steps",
                             "Training environment steps of the active run", {{"role", role}})),
        rate_(metrics.gauge("pnp_training_env_steps_per_second",
                            "Training environment steps per second of the active run",
                            {{"role", role}})),
        store_errors_(metrics.counter(
            "pnp_store_write_errors_total",
            "Store writes that failed for a reason other than a busy lock (disk full, I/O)",
            {{"role", role}})),
        store_fault_(metrics.gauge("pnp_store_fault",
                                   "1 while the store's last write failed (the service is "
                                   "NOT_SERVING), 0 otherwise",
                                   {{"role", role}})) {}

  void update(const pnp::training::RunManager::Load& load) {
    queued_.Set(static_cast<double>(load.queued));
    active_.Set(static_cast<double>(load.active.value_or(0)));
    steps_.Set(static_cast<double>(load.active_env_steps));
    rate_.Set(load.active_steps_per_s);
    // The manager counts since it started; the counter takes what is new.
    store_errors_.Increment(static_cast<double>(load.store_write_errors - counted_errors_));
    counted_errors_ = load.store_write_errors;
    store_fault_.Set(load.store_faulty ? 1 : 0);
  }

 private:
  pnp::services::Gauge &queued_, &active_, &steps_, &rate_;
  pnp::services::Counter& store_errors_;
  pnp::services::Gauge& store_fault_;
  long long counted_errors_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace pnp::services;
  catch_termination_signals();
  CLI::App app{"Train one role of the pick-and-place hierarchy as a service", "pnp-train-server"};
  // Conventional ports, one per role (deploy/ uses the same).
  const std::map<std::string, int> default_ports{{"approach", 50052},
                                                 {"manipulate", 50053},
                                                 {"retract", 50054},
                                                 {"hlc", 50055},
                                                 {"e2e", 50056}};
  std::string role, address;
  std::string db;
  std::size_t threads = 0;
  app.add_option("--role", role, "approach, manipulate, retract, hlc or e2e")->required();
  app.add_option("--address", address,
                 "host:port to listen on (port 0: any free port) [127.0.0.1:5005x by role]");
  auto* db_option = app.add_option("--db", db, "SQLite store, created if missing [$PNP_DB]");
  RemoteStoreFlags store_flags;
  add_remote_store_flags(app, store_flags, db_option);
  app.add_option("--threads", threads, "trainer threads (0: all cores)")->capture_default_str();
  std::vector<std::string> sim_addresses;
  app.add_option("--sim-address", sim_addresses,
                 "simulation services to run rollouts on: host:port, dns:///host:port (every "
                 "address the name resolves to, looked up again for each run) or "
                 "ipv4:a:p,b:p; repeatable (default: rollouts in this process)");
  double lease_s = 10;
  app.add_option("--run-lease-s", lease_s,
                 "a run whose server stops renewing its lease for this long is taken over by "
                 "another server of the role")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  int keep_checkpoints = pnp::store::RetentionPolicy{}.keep_last;
  app.add_option("--keep-checkpoints", keep_checkpoints,
                 "checkpoints kept per run besides its best, promoted and referenced ones (0: "
                 "keep all)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  std::string metrics_address;
  app.add_option("--metrics-address", metrics_address,
                 "host:port for Prometheus /metrics (port 0 picks one; empty: off)");
  ServerSecurityFlags security_flags;
  add_server_security_flags(app, security_flags);
  ClientTlsFiles sim_tls;  // how this server dials its --sim-address services
  add_client_security_flags(app, sim_tls, "sim-");
  StreamLimitOptions limit_options;
  double idle_timeout_s = 0;
  add_stream_limit_flags(app, limit_options, idle_timeout_s);
  pnp::add_version_flag(app);
  CLI11_PARSE(app, argc, argv);
  const auto port = default_ports.find(role);
  if (port == default_ports.end()) {
    std::fprintf(stderr,
                 "--role: expected one of approach, manipulate, retract, hlc, e2e, got \"%s\"\n",
                 role.c_str());
    return 2;
  }
  if (address.empty()) address = "127.0.0.1:" + std::to_string(port->second);
  const std::string name = "train-" + role;
  try {
    // Refuses a bad PNP_GEMM before serving; the path is logged with "listening".
    const std::string gemm_path(pnp::nn::gemm_path_name(pnp::nn::active_gemm_path()));
    // Before anything is created or resumed: a refused flag leaves nothing behind.
    ServerSecurity security = load_server_security(security_flags, address, metrics_address);
    validate(sim_tls);
    for (const std::string& target : sim_addresses)
      pnp::sim_client::validate_sim_target(target, "--sim-address");
    pnp::store::StoreOpener open_store;
    if (store_flags.address.empty())
      db = resolve_store_path(db, false);
    else
      open_store = remote_store_opener(store_flags.address, store_flags.tls);
    MetricsRegistry metrics;
    pnp::training::EnvironmentSource environments;
    if (!sim_addresses.empty()) {
      environments = [sim_addresses, sim_tls](pnp::sim::Robot robot, pnp::sim::ObjectShape object,
                                              pnp::sim::WorldProfile world,
                                              pnp::sim::Actuation actuation) {
        return std::make_unique<pnp::sim_client::RemoteEnvFactory>(sim_addresses, robot, object,
                                                                   world, actuation, sim_tls);
      };
    }
    pnp::training::RunManagerOptions options{db, role, std::string(pnp::kCodeCommit), threads,
                                             environments};
    options.lease = std::chrono::milliseconds(static_cast<long long>(lease_s * 1000));
    if (keep_checkpoints == 0)
      options.retention.reset();
    else
      options.retention = pnp::store::RetentionPolicy{keep_checkpoints};
    options.log = [name](const std::string& line) {
      log_event(name, "store", {{"message", line}});
    };
    options.open_store = open_store;
    // The trail is a table of the store: in the file, or through the store server.
    const auto audit = store_flags.address.empty()
                           ? open_audit_trail(db, name)
                           : open_remote_audit_trail(store_flags.address, store_flags.tls, name);
    security.audit = audit.get();
    pnp::training::RunManager manager(options);
    StreamLimits limits(stream_limit_options(limit_options, idle_timeout_s), name);
    TrainingServiceImpl service(manager, &limits);
    ServerRuntime runtime({.address = address,
                           .max_message_bytes = 4 << 20,
                           .services = {&service},
                           .service_names = {"pnp.train.v1.TrainingService"},
                           .metrics = metrics_address.empty() ? nullptr : &metrics,
                           .metrics_address = metrics_address,
                           .security = security,
                           .log_name = name});
    TrainingGauges gauges(metrics, role);
    // NOT_SERVING while the store cannot be written: a balancer or probe routes elsewhere
    // and an operator sees why in the log.
    std::optional<std::string> store_fault;
    const auto periodic = [&] {
      gauges.update(manager.load());
      auto fault = manager.store_fault();
      if (fault == store_fault) return;
      store_fault = std::move(fault);
      runtime.set_serving(!store_fault);
      if (store_fault)
        log_event(name, "store_unwritable", {{"error", *store_fault}, {"serving", false}});
      else
        log_event(name, "store_writable", {{"serving", true}});
    };
    return serve_until_terminated(runtime, name, periodic, std::chrono::milliseconds(1000),
                                  {{"db", db},
                                   {"store", store_flags.address},
                                   {"role", role},
                                   {"owner", manager.owner()},
                                   {"sim_addresses", sim_addresses},
                                   {"gemm_path", gemm_path}});
  } catch (const pnp::Error& e) {
    log_event(name, "fatal", {{"error", e.what()}});
    return 1;
  }
}
