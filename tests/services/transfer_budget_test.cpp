// The store server's bound on checkpoint bytes held for transfers: a reservation waits for
// room, one principal holds at most half, and a refusal names the flag.
#include "services/store/transfer_budget.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <optional>

#include "common/error.h"
#include "services/store/import_spool.h"
#include "tests/core/training/small_runs.h"

namespace pnp::services {
namespace {

using namespace std::chrono_literals;
constexpr std::int64_t kMiB = 1 << 20;
const auto kStays = [] { return false; };

TEST(TransferBudget, OnePrincipalHoldsAtMostHalfAndTheRefusalNamesTheFlag) {
  TransferBudget budget(8 * kMiB, 4 * kMiB, 200ms);
  const auto first = budget.reserve("approach", "SaveCheckpoint", 3 * kMiB, kStays);
  try {
    budget.reserve("approach", "SaveCheckpoint", 2 * kMiB, kStays);
    FAIL() << "a principal passed its share";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
    EXPECT_NE(std::string(e.what()).find("--max-transfer-mb"), std::string::npos) << e.what();
  }
  // Another principal still finds room, up to the whole budget.
  const auto other = budget.reserve("retract", "SaveCheckpoint", 4 * kMiB, kStays);
  EXPECT_EQ(budget.held_bytes(), 7 * kMiB);
  EXPECT_THROW(budget.reserve("ops", "LoadCheckpoint", 2 * kMiB, kStays), Error);
}

TEST(TransferBudget, AWaitingTransferGetsTheRoomAReleaseLeaves) {
  TransferBudget budget(8 * kMiB, 4 * kMiB, 30s);
  std::optional<TransferBudget::Reservation> held(
      budget.reserve("approach", "SaveCheckpoint", 4 * kMiB, kStays));
  auto waiting = std::async(std::launch::async, [&] {
    return budget.reserve("approach", "SaveCheckpoint", 4 * kMiB, kStays);
  });
  EXPECT_EQ(waiting.wait_for(300ms), std::future_status::timeout);
  held.reset();
  const auto got = waiting.get();
  EXPECT_EQ(budget.held_bytes(), 4 * kMiB);
}

TEST(TransferBudget, ACallerThatLeavesStopsWaiting) {
  TransferBudget budget(8 * kMiB, 4 * kMiB, 30s);
  const auto held = budget.reserve("", "SaveCheckpoint", 8 * kMiB, kStays);
  try {
    budget.reserve("", "SaveCheckpoint", 1, [] { return true; });
    FAIL() << "a caller that left was still waiting";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
  }
}

TEST(TransferBudget, ABudgetWithoutRoomForTwoLargestCheckpointsIsRefusedAtStart) {
  try {
    TransferBudget(100 * kMiB, 64 * kMiB);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("--max-transfer-mb: expected at least twice"),
              std::string::npos)
        << e.what();
  }
}

TEST(ImportSpool, BlobsComeBackAsWrittenAndTheFileGoesWithTheSpool) {
  const training::testing::ScratchDir dir("import_spool");
  std::string path;
  {
    ImportSpool spool(dir.file("pnp.db"));
    path = spool.path();
    const std::vector<std::uint8_t> a{1, 2, 3}, b(300'000, 7);
    const auto sa = spool.write(a);
    const auto sb = spool.write(b);
    EXPECT_EQ(spool.read(sb), b);
    EXPECT_EQ(spool.read(sa), a);
    EXPECT_TRUE(std::filesystem::exists(path));
    EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::all,
              std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace pnp::services
