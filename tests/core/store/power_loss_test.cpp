// A power loss never takes back what the store acknowledged (synchronous FULL), modelled
// by a VFS that keeps only what was synced (power_loss_vfs.h): the database a machine
// would find after losing power right after any acknowledged write holds every run,
// state, evaluation and promotion acknowledged before it, and passes integrity_check.
// The same writes with synchronous NORMAL lose acknowledged commits, which is why the
// store does not use it (and shows that the model bites).
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "common/rng.h"
#include "store/run_store.h"
#include "tests/core/store/power_loss_vfs.h"
#include "tests/core/store/store_fixture.h"

namespace pnp::store {
namespace {

// What a client has been told is stored.
struct Acknowledged {
  std::map<std::int64_t, RunState> runs;
  std::map<std::int64_t, std::size_t> evaluations;
  std::map<std::string, std::int64_t> promotions;
};

// Whether the database in `dir` holds everything in `truth`; the first difference if not.
std::string missing_from(const std::string& path, const Acknowledged& truth) {
  RunStore store(path);
  auto integrity = store.database().prepare("PRAGMA integrity_check");
  integrity.step();
  if (integrity.column_text(0) != "ok") return "integrity_check: " + integrity.column_text(0);
  for (const auto& [id, state] : truth.runs) {
    try {
      const RunRecord run = store.get_run(id);
      if (run.state != state) return "run " + std::to_string(id) + " has an earlier state";
      if (store.metrics(id).size() < truth.evaluations.at(id))
        return "run " + std::to_string(id) + " lost evaluations";
    } catch (const Error&) {
      return "run " + std::to_string(id) + " lost";
    }
  }
  for (const auto& [role, checkpoint] : truth.promotions) {
    const auto promoted = store.promoted(role);
    if (!promoted || promoted->checkpoint_id != checkpoint) return "promotion of " + role + " lost";
  }
  return "";
}

// Writes as the platform does (runs created, claimed, evaluated with their checkpoints,
// finished, promoted) and cuts the power after each of `cuts` seeded writes; returns how
// many of those cuts lost something acknowledged.
int lossy_cuts(const std::filesystem::path& dir, Sync sync, int cuts, std::uint64_t seed) {
  testing::PowerLossVfs vfs("power_loss_" + std::to_string(static_cast<int>(sync)));
  const std::filesystem::path live = dir / "live";
  std::filesystem::create_directories(live);
  const std::string path = (live / "pnp.db").string();
  RunStore store(path, {.sync = sync, .vfs = vfs.name()});
  Rng rng(seed);
  Acknowledged truth;
  std::vector<std::uint8_t> blob(5000);
  int lost = 0;
  for (int cut = 0; cut < cuts; ++cut) {
    const int writes = 1 + static_cast<int>(rng.next_u64() % 6);
    for (int w = 0; w < writes; ++w) {
      const RunRecord run = store.create_run(
          {"approach", "ddpg_her", "fetch", "block", 1, "{}", "test", std::nullopt});
      truth.runs[run.id] = RunState::kPending;
      truth.evaluations[run.id] = 0;
      store.claim_next("approach", "owner", std::chrono::hours(1));
      truth.runs[run.id] = RunState::kRunning;
      for (auto& b : blob) b = static_cast<std::uint8_t>(rng.next_u64());
      const MetricPoint point{1000, 10, 1.0, 0.5, 0.5, 0.5, 0.1, 0.1, 40};
      const auto checkpoint = store.record_evaluation(run.id, point, blob, false, {}, "owner");
      truth.evaluations[run.id] = 1;
      store.set_state(run.id, RunState::kSucceeded, "", "owner");
      truth.runs[run.id] = RunState::kSucceeded;
      store.promote(checkpoint.id);
      truth.promotions["approach"] = checkpoint.id;
    }
    const std::filesystem::path after = dir / ("cut_" + std::to_string(cut));
    vfs.power_cut(live, after);
    if (!missing_from((after / "pnp.db").string(), truth).empty()) ++lost;
  }
  return lost;
}

TEST_F(StoreTest, APowerLossKeepsEveryAcknowledgedCommit) {
  EXPECT_EQ(lossy_cuts(dir_ / "full", Sync::kFull, 12, 11), 0);
}

TEST_F(StoreTest, APowerLossWithSynchronousNormalLosesAcknowledgedCommits) {
  EXPECT_GT(lossy_cuts(dir_ / "normal", Sync::kNormal, 12, 11), 0)
      << "the model of a power loss shows what synchronous NORMAL would lose";
}

}  // namespace
}  // namespace pnp::store
