#pragma once
// Counts the heap allocations the calling thread makes, for tests that pin a hot loop as
// allocation-free. allocation_counter.cpp replaces malloc and its siblings in the test
// binary that links it (forwarding to glibc's own), so it sees operator new, Eigen's
// aligned blocks and std::vector alike; calls from inside OpenBLAS are left out (its
// kernels' scratch depends on the CPU, not on our code). Where that cannot work (a sanitizer's
// allocator owns malloc, or the libc is not glibc) counting_allocations() is false and a test
// skips.

#include <cstddef>

namespace pnp::test {

bool counting_allocations();
// Allocations (malloc, calloc, realloc, aligned) made by this thread so far.
std::size_t allocations_on_this_thread();

}  // namespace pnp::test
