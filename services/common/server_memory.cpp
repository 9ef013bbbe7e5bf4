#include "services/common/server_memory.h"

#include "common/sanitizers.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace pnp::services {

bool keep_large_blocks_mapped() {
#if defined(__GLIBC__) && !defined(PNP_SANITIZER_ALLOCATOR)
  return mallopt(M_MMAP_THRESHOLD, static_cast<int>(kLargeBlockBytes)) == 1;
#else
  return false;  // the sanitizers bring their own allocator
#endif
}

}  // namespace pnp::services
