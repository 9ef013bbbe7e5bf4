// pnp-bench-store: what the store's durability costs and what retention saves.
//
// One simulated training run, written as the training service writes it: every
// evaluation is a metric and its checkpoint in one transaction, by the run's owner. The
// same run is written three times into fresh files: synchronous FULL (the store's
// setting: an acknowledged commit survives a power loss), synchronous NORMAL (survives a
// process crash only; the peer measured in the same run), and FULL with the service's
// default retention (pruned after every evaluation). Prints JSON: evaluations committed
// per second for each, FULL's cost as a ratio to NORMAL, and the disk use (database and
// WAL) of the run with and without retention.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/rng.h"
#include "store/run_store.h"
#include "tools/common/cli.h"

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

Pass write_run(const std::filesystem::path& db, store::Sync sync,
               std::optional<store::RetentionPolicy> retention, int evaluations, long long interval,
               const std::vector<std::uint8_t>& blob) {
  std::filesystem::remove(db);
  std::filesystem::remove(db.string() + "-wal");
  std::filesystem::remove(db.string() + "-shm");
  store::RunStore s(db.string(), {.sync = sync});
  const auto run = s.create_run({"retract", "ddpg_her", "panda", "block", 0, "{}", "bench", {}});
  s.claim_next("retract", "bench", std::chrono::hours(1));
  Pass pass;
  const auto t0 = Clock::now();
  for (int k = 1; k <= evaluations; ++k) {
    const store::MetricPoint point{k * interval, k * 20LL, k * 1.0, 0.5,     0.5,
                                   0.5,          0.1,      0.1,     k * 40LL};
    s.record_evaluation(run.id, point, blob, false, std::nullopt, "bench");
    if (retention) s.prune_checkpoints(run.id, *retention);
  }
  pass.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  s.database().execute("PRAGMA wal_checkpoint(TRUNCATE)");
  pass.disk_bytes = disk_use(db);
  pass.checkpoints = static_cast<std::int64_t>(s.checkpoints(run.id).size());
  return pass;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pnp-bench-store: the cost of durable commits and the saving of retention"};
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
  app.add_option("--dir", dir, "where the three database files are written (a local disk)")
      ->capture_default_str();
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
    };
    std::printf("%s\n", out.dump(2).c_str());
    for (const char* name : {"full.db", "normal.db", "retained.db"})
      for (const char* suffix : {"", "-wal", "-shm"})
        std::filesystem::remove(root / (std::string(name) + suffix));
  });
}
