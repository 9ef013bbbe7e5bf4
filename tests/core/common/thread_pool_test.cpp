#include "common/thread_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace pnp {
namespace {

TEST(ThreadPool, VisitsEveryIndexExactlyOnce) {
  for (std::size_t threads : {1u, 2u, 3u, 8u}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.size(), threads);
    for (std::size_t n : {0u, 1u, 2u, 7u, 1000u}) {
      std::vector<std::atomic<int>> hits(n);
      pool.parallel_for(n, [&](std::size_t i) { hits[i].fetch_add(1); });
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << "n=" << n << " i=" << i;
    }
  }
}

TEST(ThreadPool, ReusableAcrossManyLoops) {
  ThreadPool pool(3);
  std::atomic<long> sum{0};
  for (int round = 0; round < 500; ++round) {
    pool.parallel_for(10, [&](std::size_t i) { sum += static_cast<long>(i); });
  }
  EXPECT_EQ(sum.load(), 500L * 45);
}

TEST(ThreadPool, RethrowsTheWorkersExceptionAfterAllChunksFinish) {
  ThreadPool pool(2);
  std::atomic<int> done{0};
  EXPECT_THROW(pool.parallel_for(100,
                                 [&](std::size_t i) {
                                   if (i == 73) throw std::runtime_error("boom");
                                   ++done;
                                 }),
               std::runtime_error);
  // The pool is still usable afterwards.
  std::atomic<int> after{0};
  pool.parallel_for(10, [&](std::size_t) { ++after; });
  EXPECT_EQ(after.load(), 10);
}

}  // namespace
}  // namespace pnp
