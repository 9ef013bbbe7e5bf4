#include "common/shared_snapshot.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace pnp {
namespace {

// Each snapshot's fields agree with each other: a reader that saw half of one store and
// half of the next would find first != second.
struct Pair {
  int first = 0;
  int second = 0;
};

TEST(SharedSnapshot, StartsEmptyAndHandsOutWhatWasStored) {
  SharedSnapshot<Pair> snapshot;
  EXPECT_EQ(snapshot.load(), nullptr);
  snapshot.store(std::make_shared<const Pair>(Pair{3, 3}));
  ASSERT_NE(snapshot.load(), nullptr);
  EXPECT_EQ(snapshot.load()->first, 3);
}

TEST(SharedSnapshot, AReaderKeepsItsSnapshotAfterAReplacement) {
  SharedSnapshot<Pair> snapshot(std::make_shared<const Pair>(Pair{1, 1}));
  const auto held = snapshot.load();
  snapshot.store(std::make_shared<const Pair>(Pair{2, 2}));
  EXPECT_EQ(held->first, 1);  // still alive: the reader owns a reference
  EXPECT_EQ(held.use_count(), 1);
  EXPECT_EQ(snapshot.load()->first, 2);
}

// Under ThreadSanitizer (scripts/test --sanitize thread) this is the check that each
// replacement is ordered after every read of the snapshot it replaces. The writer empties
// the snapshot between values, as a server starts with nothing to serve: an empty
// shared_ptr has no reference count whose atomics would order the reads on their own
// (std::atomic<std::shared_ptr> in GCC 12 fails here).
TEST(SharedSnapshot, ReadersSeeWholeSnapshotsWhileAWriterReplacesThem) {
  SharedSnapshot<Pair> snapshot;
  std::atomic<bool> done{false};
  std::atomic<int> torn{0};
  std::vector<std::jthread> readers;
  for (int r = 0; r < 3; ++r) {
    readers.emplace_back([&] {
      int last = 0;
      while (!done.load()) {
        const auto seen = snapshot.load();
        if (!seen) continue;
        if (seen->first != seen->second || seen->first < last) torn.fetch_add(1);
        last = seen->first;
      }
    });
  }
  for (int k = 1; k <= 2000; ++k) {
    snapshot.store(k % 2 == 0 ? std::make_shared<const Pair>(Pair{k, k}) : nullptr);
  }
  done.store(true);
  readers.clear();
  EXPECT_EQ(torn.load(), 0);
  ASSERT_NE(snapshot.load(), nullptr);
  EXPECT_EQ(snapshot.load()->first, 2000);
}

}  // namespace
}  // namespace pnp
