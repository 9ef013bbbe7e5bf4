#include "support/allocation_counter.h"

#include <cblas.h>
#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace pnp::test {
namespace {

// The allocation-free tests rest on this counter: it must see our allocations, or they
// could never fail.
TEST(AllocationCounter, CountsTheAllocationsOfOurCode) {
  if (!counting_allocations()) GTEST_SKIP() << "no counting allocator in this build";
  const std::size_t before = allocations_on_this_thread();
  auto block = std::make_unique<std::vector<float>>(1000);
  EXPECT_GE(allocations_on_this_thread() - before, 2u) << "the vector and its buffer";
  EXPECT_EQ(block->size(), 1000u);
}

// OpenBLAS's small-matrix kernels allocate scratch on every call on some CPUs (Cooper
// Lake, Zen 4) and never on others: that is not ours to pin, so it is not counted.
TEST(AllocationCounter, LeavesOutOpenBlasScratch) {
  if (!counting_allocations()) GTEST_SKIP() << "no counting allocator in this build";
  // A one-output layer onto its bias (beta 1): the call that allocates on a Zen 4.
  std::vector<float> a(64, 0.5f), b(64 * 32, 0.25f), c(32, 0.0f);
  const auto multiply = [&] {
    cblas_sgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, 1, 32, 64, 1.0f, a.data(), 1, b.data(),
                64, 1.0f, c.data(), 1);
  };
  multiply();  // any first-call set-up
  const std::size_t before = allocations_on_this_thread();
  multiply();
  EXPECT_EQ(allocations_on_this_thread() - before, 0u);
  EXPECT_FLOAT_EQ(c[31], 2 * 64 * 0.5f * 0.25f);
}

}  // namespace
}  // namespace pnp::test
