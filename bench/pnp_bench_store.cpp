// pnp-bench-store: what the store's durability costs, what retention saves, and what
// reaching the store through pnp-store-server costs beside opening the file.
//
// One simulated training run, written as the training service writes it: every
// evaluation is a metric and its checkpoint in one transaction, by the run's owner. The
// same run is written three times into fresh files: synchronous FULL (the store's
// setting: an acknowledged commit survives a power loss), synchronous NORMAL (survives a
// process crash only; the peer measured in the same run), and FULL with the service's
// default retention (pruned after every evaluation). Prints JSON: evaluations committed
// per second for each, FULL's cost as a ratio to NORMAL, and the disk use (database and
// WAL) of the run with and without retention. Then the same store operations in process
// (RunStore) and through the store service on loopback (RemoteStore, a real server in
// this process), each measured in the same run: metric writes per second, checkpoint round
// trips (save, then load and verify), and the training run's writes with retention.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/rng.h"
#include "services/common/server_runtime.h"
#include "services/store/checkpoint_chunks.h"
#include "services/store/remote_store.h"
#include "services/store/store_service.h"
#include "store/run_store.h"
#include "tools/common/cli.h"
#include "training/preset.h"
#include "training/run_manager.h"

namespace {

using Clock = std::chrono::steady_clock;
namespace store = pnp::store;

struct Pass {
  double seconds = 0;
  std::uintmax_t disk_bytes = 0;
  std::int64_t checkpoints = 0;
};

std::uintmax_t disk_use(const std::filesystem::path& db) {
  std::uintmax_t total = 0;
  for (const char* suffix : {"", "-wal", "-shm"}) {
    const std::filesystem::path file = db.string() + suffix;
    if (std::filesystem::exists(file)) total += std::filesystem::file_size(file);
  }
  return total;
}

void remove_database(const std::filesystem::path& db) {
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db.string() + suffix);
}

store::RunRecord owned_run(store::Store& s) {
  const auto run = s.create_run({"retract", "ddpg_her", "panda", "block", 0, "{}", "bench", {}});
  s.claim_next("retract", "bench", std::chrono::hours(1));
  return run;
}

// The evaluations of one training run (metric and checkpoint in one transaction, pruned
// after each with `retention`), written through `s`: seconds taken.
double write_evaluations(store::Store& s, std::optional<store::RetentionPolicy> retention,
                         int evaluations, long long interval,
                         const std::vector<std::uint8_t>& blob) {
  const auto run = owned_run(s);
  const auto t0 = Clock::now();
  for (int k = 1; k <= evaluations; ++k) {
    const store::MetricPoint point{k * interval, k * 20LL, k * 1.0, 0.5,     0.5,
                                   0.5,          0.1,      0.1,     k * 40LL};
    s.record_evaluation(run.id, point, blob, false, std::nullopt, "bench");
    if (retention) s.prune_checkpoints(run.id, *retention);
  }
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// `count` learning-curve points written one transaction each: seconds taken.
double write_metrics(store::Store& s, int count) {
  const auto run = owned_run(s);
  const auto t0 = Clock::now();
  for (int k = 1; k <= count; ++k) {
    s.record_metric(run.id, {k * 1000LL, k * 20LL, k * 1.0, 0.5, 0.5, 0.5, 0.1, 0.1, k * 40LL},
                    false, std::nullopt, "bench");
  }
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// `count` checkpoints saved and loaded back (verified by the store): seconds taken.
double round_trip_checkpoints(store::Store& s, int count, const std::vector<std::uint8_t>& blob) {
  const auto run = owned_run(s);
  const auto t0 = Clock::now();
  for (int k = 1; k <= count; ++k) {
    const auto info = s.save_checkpoint(run.id, k, 0.5, blob, "bench");
    if (s.load_checkpoint(info.id).blob.size() != blob.size())
      throw std::runtime_error("a checkpoint came back with another size");
  }
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Peer {
  double embedded_s = 0, remote_s = 0;
};

// Runs `work` on a fresh file opened in process, then on another fresh file behind a store
// server on loopback reached through RemoteStore.
template <typename Work>
Peer embedded_and_remote(const std::filesystem::path& root, const std::string& name, Work work,
                         bool remote_first = false) {
  Peer peer;
  const auto embedded_db = root / (name + "_embedded.db");
  const auto remote_db = root / (name + "_remote.db");
  remove_database(embedded_db);
  remove_database(remote_db);
  const auto embedded = [&] {
    store::RunStore s(embedded_db.string());
    peer.embedded_s = work(s);
  };
  if (!remote_first) embedded();
  {
    // Storage is measured: any bytes are a checkpoint here, as in the embedded peer.
    pnp::services::StoreServiceImpl service(
        remote_db.string(),
        [](std::string_view, std::span<const std::uint8_t>, std::string_view) {});
    pnp::services::ServerRuntime server({.address = "127.0.0.1:0",
                                         .max_message_bytes = pnp::services::kStoreMessageBytes,
                                         .services = {&service},
                                         .service_names = {"pnp.store.v1.StoreService"},
                                         .metrics = nullptr,
                                         .metrics_address = {},
                                         .security = {},
                                         .log_name = "store"});
    const std::string address = "127.0.0.1:" + std::to_string(server.port());
    pnp::services::RemoteStore s(
        grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(),
                                  pnp::services::store_channel_arguments()),
        address);
    peer.remote_s = work(s);
    server.shutdown(std::chrono::milliseconds(500));
  }
  if (remote_first) embedded();
  remove_database(embedded_db);
  remove_database(remote_db);
  return peer;
}

// One real training run, the default preset's approach expert (seed 1, one trainer
// thread), by a RunManager whose store is `open_store` (empty: the file `db` in process):
// seconds from its creation to its end, and its steps.
struct TrainedRun {
  double seconds = 0;
  long long env_steps = 0;
};

TrainedRun train_once(const std::string& db, pnp::store::StoreOpener open_store) {
  using namespace pnp::training;
  RunManagerOptions options{db, "approach", "bench", 1};
  options.open_store = std::move(open_store);
  RunManager manager(options);
  TrainingSpec spec = preset_spec(find_preset(kDefaultPreset, "preset"), "approach");
  spec.seed = 1;
  const auto t0 = Clock::now();
  const auto run = manager.create(spec, {});
  std::uint64_t seen = manager.generation();
  while (!store::is_terminal(manager.get(run.id).state))
    seen = manager.wait_for_change(seen, std::chrono::milliseconds(50));
  const auto done = manager.get(run.id);
  if (done.state != store::RunState::kSucceeded)
    throw std::runtime_error("the benchmark's training run ended " +
                             std::string(store::run_state_name(done.state)) + ": " + done.error);
  return {std::chrono::duration<double>(Clock::now() - t0).count(), done.env_steps};
}

Pass write_run(const std::filesystem::path& db, store::Sync sync,
               std::optional<store::RetentionPolicy> retention, int evaluations, long long interval,
               const std::vector<std::uint8_t>& blob) {
  remove_database(db);
  store::RunStore s(db.string(), {.sync = sync});
  Pass pass;
  pass.seconds = write_evaluations(s, retention, evaluations, interval, blob);
  s.database().execute("PRAGMA wal_checkpoint(TRUNCATE)");
  pass.disk_bytes = disk_use(db);
  pass.checkpoints = static_cast<std::int64_t>(s.checkpoints(s.list_runs().front().id).size());
  return pass;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The cost of durable commits and the saving of retention", "pnp-bench-store"};
  int evaluations = 200;
  long long interval = 1000;
  std::size_t blob_bytes = 1'100'000;
  std::string dir = (std::filesystem::temp_directory_path() / "pnp-bench-store").string();
  app.add_option("--evaluations", evaluations,
                 "evaluations of the run (200 at the default interval: a 200k-step run)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--eval-interval", interval, "training steps between evaluations")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--blob-bytes", blob_bytes,
                 "checkpoint size (1.1 MB: an expert of three 256-wide layers with its critic)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--dir", dir, "where the database files are written (a local disk)")
      ->capture_default_str();
  int metric_writes = 500, round_trips = 50;
  int training_pairs = 3;
  app.add_option("--training-pairs", training_pairs,
                 "real training runs (the default preset's approach expert) in process and "
                 "through the service, alternating; 0 skips them")
      ->capture_default_str()
      ->check(CLI::Range(0, 100));
  app.add_option("--metric-writes", metric_writes,
                 "learning-curve points written in process and through the service")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--round-trips", round_trips,
                 "checkpoints saved and loaded back in process and through the service")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  return pnp::tools::run_tool(app, argc, argv, [&] {
    std::filesystem::create_directories(dir);
    // Incompressible bytes, as trained weights are; the seed fixes them.
    pnp::Rng rng(7);
    std::vector<std::uint8_t> blob(blob_bytes);
    for (auto& b : blob) b = static_cast<std::uint8_t>(rng.next_u64() & 0xff);
    const std::filesystem::path root(dir);
    const Pass full =
        write_run(root / "full.db", store::Sync::kFull, std::nullopt, evaluations, interval, blob);
    const Pass normal = write_run(root / "normal.db", store::Sync::kNormal, std::nullopt,
                                  evaluations, interval, blob);
    const store::RetentionPolicy policy{};
    const Pass kept =
        write_run(root / "retained.db", store::Sync::kFull, policy, evaluations, interval, blob);
    const auto rate = [&](const Pass& p) { return evaluations / p.seconds; };
    const Peer metrics = embedded_and_remote(
        root, "metrics", [&](store::Store& s) { return write_metrics(s, metric_writes); });
    const Peer trips = embedded_and_remote(root, "round_trips", [&](store::Store& s) {
      return round_trip_checkpoints(s, round_trips, blob);
    });
    const Peer training = embedded_and_remote(root, "training", [&](store::Store& s) {
      return write_evaluations(s, policy, evaluations, interval, blob);
    });
    nlohmann::json trained = nullptr;
    if (training_pairs > 0) {
      // Pairs in alternating order: the machine's drift between two runs is larger than
      // what the store costs, so the ratio is read as a median over pairs.
      std::vector<double> ratios;
      nlohmann::json pairs = nlohmann::json::array();
      for (int pair = 0; pair < training_pairs; ++pair) {
        std::optional<TrainedRun> embedded_run, remote_run;
        const auto train = [&](store::Store& s) {
          // The handle the peer opened says where the store is; the manager opens its own.
          if (auto* remote = dynamic_cast<pnp::services::RemoteStore*>(&s)) {
            remote_run = train_once("", pnp::services::remote_store_opener(remote->address(), {}));
          } else {
            embedded_run = train_once(dynamic_cast<store::RunStore&>(s).database().path(), {});
          }
          return 0.0;
        };
        embedded_and_remote(root, "trained", train, /*remote_first=*/pair % 2 == 1);
        ratios.push_back(remote_run->seconds / embedded_run->seconds);
        pairs.push_back({{"embedded_wall_s", embedded_run->seconds},
                         {"remote_wall_s", remote_run->seconds},
                         {"embedded_env_steps", embedded_run->env_steps},
                         {"remote_env_steps", remote_run->env_steps}});
      }
      std::sort(ratios.begin(), ratios.end());
      trained = {{"role", "approach"},
                 {"preset", pnp::training::kDefaultPreset},
                 {"seed", 1},
                 {"pairs", pairs},
                 {"wall_remote_over_embedded_median", ratios[ratios.size() / 2]}};
    }
    const nlohmann::json through_service{
        {"training_run", trained},
        {"metric_writes", metric_writes},
        {"metric_writes_per_s",
         {{"embedded", metric_writes / metrics.embedded_s},
          {"remote", metric_writes / metrics.remote_s}}},
        {"metric_write_time_remote_over_embedded", metrics.remote_s / metrics.embedded_s},
        {"checkpoint_round_trips", round_trips},
        {"ms_per_checkpoint_round_trip",
         {{"embedded", 1e3 * trips.embedded_s / round_trips},
          {"remote", 1e3 * trips.remote_s / round_trips}}},
        {"round_trip_time_remote_over_embedded", trips.remote_s / trips.embedded_s},
        {"training_run_writes_s",
         {{"embedded", training.embedded_s}, {"remote", training.remote_s}}},
        {"training_run_writes_remote_over_embedded", training.remote_s / training.embedded_s},
    };
    const nlohmann::json out{
        {"evaluations", evaluations},
        {"env_steps", evaluations * interval},
        {"blob_bytes", blob_bytes},
        {"full", {{"evaluations_per_s", rate(full)}, {"ms_per_evaluation", 1e3 / rate(full)}}},
        {"normal",
         {{"evaluations_per_s", rate(normal)}, {"ms_per_evaluation", 1e3 / rate(normal)}}},
        {"full_time_over_normal", full.seconds / normal.seconds},
        {"full_with_retention",
         {{"evaluations_per_s", rate(kept)}, {"ms_per_evaluation", 1e3 / rate(kept)}}},
        {"keep_last", policy.keep_last},
        {"disk_bytes_without_retention", full.disk_bytes},
        {"disk_bytes_with_retention", kept.disk_bytes},
        {"checkpoints_without_retention", full.checkpoints},
        {"checkpoints_with_retention", kept.checkpoints},
        {"disk_ratio", static_cast<double>(full.disk_bytes) / static_cast<double>(kept.disk_bytes)},
        {"through_the_store_service", through_service},
    };
    std::printf("%s\n", out.dump(2).c_str());
    for (const char* name : {"full.db", "normal.db", "retained.db"})
      for (const char* suffix : {"", "-wal", "-shm"})
        std::filesystem::remove(root / (std::string(name) + suffix));
  });
}
