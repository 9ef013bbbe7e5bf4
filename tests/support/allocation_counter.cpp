#include "support/allocation_counter.h"

#include <link.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "common/sanitizers.h"

#if defined(__GLIBC__) && !defined(PNP_SANITIZER_ALLOCATOR)
#define PNP_COUNT_ALLOCATIONS 1
#endif

namespace pnp::test {
namespace {
// Per thread, so a test counts only its own calls; constant-initialised, so reading it
// never allocates.
thread_local std::size_t allocations = 0;

// OpenBLAS's own scratch is not ours to pin: some of its kernels allocate on every call
// on some CPUs (sgemm_small_kernel_nn_COOPERLAKE, on a Zen 4), others never. Calls made
// from inside its code are not counted, so a test pins our code on every CPU.
struct CodeRange {
  std::uintptr_t begin = 0, end = 0;
  bool contains(const void* address) const {
    const auto a = reinterpret_cast<std::uintptr_t>(address);
    return a >= begin && a < end;
  }
};

int find_blas_code(dl_phdr_info* info, std::size_t, void* out) {
  if (info->dlpi_name == nullptr || std::strstr(info->dlpi_name, "libopenblas") == nullptr)
    return 0;
  auto& range = *static_cast<CodeRange*>(out);
  for (int k = 0; k < info->dlpi_phnum; ++k) {
    const ElfW(Phdr)& segment = info->dlpi_phdr[k];
    if (segment.p_type != PT_LOAD || (segment.p_flags & PF_X) == 0) continue;
    range.begin = info->dlpi_addr + segment.p_vaddr;
    range.end = range.begin + segment.p_memsz;
  }
  return 1;
}

CodeRange locate_blas_code() {
  CodeRange range;
  dl_iterate_phdr(find_blas_code, &range);
  return range;
}

// Found once while the program loads (OpenBLAS is linked, so already mapped); until then
// it is empty and every allocation counts.
const CodeRange blas_code = locate_blas_code();

void count_allocation_from(const void* caller) {
  if (!blas_code.contains(caller)) ++allocations;
}
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
  pnp::test::count_allocation_from(__builtin_return_address(0));
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) noexcept {
  pnp::test::count_allocation_from(__builtin_return_address(0));
  return __libc_calloc(count, size);
}
void* realloc(void* block, std::size_t size) noexcept {
  pnp::test::count_allocation_from(__builtin_return_address(0));
  return __libc_realloc(block, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  pnp::test::count_allocation_from(__builtin_return_address(0));
  return __libc_memalign(alignment, size);
}
void* memalign(std::size_t alignment, std::size_t size) noexcept {
  pnp::test::count_allocation_from(__builtin_return_address(0));
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return EINVAL;
  pnp::test::count_allocation_from(__builtin_return_address(0));
  void* block = __libc_memalign(alignment, size);
  if (!block && size != 0) return ENOMEM;
  *out = block;
  return 0;
}
}
#endif
