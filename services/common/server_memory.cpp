#include "services/common/server_memory.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace pnp::services {

bool keep_large_blocks_mapped() {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
  return mallopt(M_MMAP_THRESHOLD, static_cast<int>(kLargeBlockBytes)) == 1;
#else
  return false;  // the sanitizers bring their own allocator
#endif
}

}  // namespace pnp::services
