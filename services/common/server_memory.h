#pragma once
// How a long-running server's allocator treats large blocks. glibc serves a block above
// its mmap threshold (128 KiB at start) with its own mapping, returned to the system on
// free, but raises the threshold to the size of each such block freed, up to 32 MiB. After
// that, the blocks a server allocates and frees all day (a 7 MB mjData per environment,
// networks and replay buffers per training run, a transient mjData per world loaded) come
// from the heap arenas instead, where the pages a freed block touched stay resident and the
// next block lands elsewhere: the process's RSS creeps up while the memory it uses stays
// flat (measured with heaptrack under pnp-bench-soak; docs/RELIABILITY.md, "Soak").
// Pinning the threshold keeps large blocks in mappings of their own (unless free heap
// space already fits one), so a freed block gives its pages back.

#include <cstddef>

namespace pnp::services {

// glibc's own starting threshold: pinning it there only stops the raising. (1 MiB did as
// well for the simulation and training servers; the inference server's RSS then took
// 3.5 minutes instead of 2 to level off, 8% above its level at minute 2.)
inline constexpr std::size_t kLargeBlockBytes = std::size_t{128} << 10;

// Fixes glibc's mmap threshold at kLargeBlockBytes (which also fixes its trim threshold at
// its default instead of following it). Returns false where the allocator is not glibc's
// or refused the setting (a sanitizer's allocator, another libc): then nothing changed.
bool keep_large_blocks_mapped();

}  // namespace pnp::services
