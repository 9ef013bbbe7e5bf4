#include "support/allocation_counter.h"

#include <cerrno>
#include <cstddef>
#include <cstdlib>

#include "common/sanitizers.h"

#if defined(__GLIBC__) && !defined(PNP_SANITIZER_ALLOCATOR)
#define PNP_COUNT_ALLOCATIONS 1
#endif

namespace pnp::test {
namespace {
// Per thread, so a test counts only its own calls; constant-initialised, so reading it
// never allocates.
thread_local std::size_t allocations = 0;
}  // namespace

#if defined(PNP_COUNT_ALLOCATIONS)
bool counting_allocations() {
  return true;
}
#else
bool counting_allocations() {
  return false;
}
#endif

std::size_t allocations_on_this_thread() {
  return allocations;
}

}  // namespace pnp::test

#if defined(PNP_COUNT_ALLOCATIONS)
// glibc's own entry points, which its malloc, calloc, ... are aliases of.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* block, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);

void* malloc(std::size_t size) noexcept {
  ++pnp::test::allocations;
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) noexcept {
  ++pnp::test::allocations;
  return __libc_calloc(count, size);
}
void* realloc(void* block, std::size_t size) noexcept {
  ++pnp::test::allocations;
  return __libc_realloc(block, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  ++pnp::test::allocations;
  return __libc_memalign(alignment, size);
}
void* memalign(std::size_t alignment, std::size_t size) noexcept {
  ++pnp::test::allocations;
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return EINVAL;
  ++pnp::test::allocations;
  void* block = __libc_memalign(alignment, size);
  if (!block && size != 0) return ENOMEM;
  *out = block;
  return 0;
}
}
#endif
