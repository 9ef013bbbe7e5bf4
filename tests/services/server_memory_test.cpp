#include "services/common/server_memory.h"

#include <gtest/gtest.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstddef>
#include <memory>

namespace pnp::services {
namespace {

#if defined(__GLIBC__)
// Allocates `bytes`, touches every page, and says whether the block has its own mapping.
bool block_is_mapped(std::size_t bytes) {
  const std::size_t before = mallinfo2().hblks;
  auto block = std::make_unique<char[]>(bytes);
  volatile char* pages = block.get();
  for (std::size_t i = 0; i < bytes; i += 4096) pages[i] = 1;
  return mallinfo2().hblks > before;
}
#endif

TEST(ServerMemory, LargeBlocksKeepTheirOwnMappingAfterLargerOnesAreFreed) {
#if defined(__GLIBC__)
  if (!keep_large_blocks_mapped()) GTEST_SKIP() << "not glibc's allocator (a sanitizer's)";
  // Unpinned, freeing the 16 MiB block would raise glibc's threshold past 8 MiB, and the
  // 8 MiB block would come from (and stay resident in) the heap. (A block is still served
  // from free heap space that fits it, so this runs in a process of its own: its test
  // binary holds nothing else.)
  EXPECT_TRUE(block_is_mapped(16u << 20));
  EXPECT_TRUE(block_is_mapped(8u << 20));
  EXPECT_FALSE(block_is_mapped(kLargeBlockBytes / 8)) << "small blocks stay in the heap";
#else
  GTEST_SKIP() << "the threshold is glibc's";
#endif
}

}  // namespace
}  // namespace pnp::services
