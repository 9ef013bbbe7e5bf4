#pragma once
// Tells ThreadSanitizer about an ordering it cannot see: an object of ours that an
// uninstrumented library (Debian's gRPC) calls on its own threads and destroys on another.
// The library orders those steps with its own locks and reference counts, invisible to TSan,
// so without these the constructor's writes, each call's reads and the destructor look like
// races. They compile to nothing in other builds.
//
//   constructor: publish_handover(this);
//   each call:   const HandoverScope handover(this);   (sees the constructor; its accesses
//                                                      are seen by later calls and the end)
//   destructor:  receive_handover(this);

#include "common/sanitizers.h"

#ifdef PNP_SANITIZER_THREAD
#include <sanitizer/tsan_interface.h>
#endif

namespace pnp {

// What this thread did so far happens before whatever a later receive_handover(key) does.
inline void publish_handover([[maybe_unused]] const void* key) {
#ifdef PNP_SANITIZER_THREAD
  __tsan_release(const_cast<void*>(key));
#endif
}

// What the threads that published `key` did happens before what this thread does next.
inline void receive_handover([[maybe_unused]] const void* key) {
#ifdef PNP_SANITIZER_THREAD
  __tsan_acquire(const_cast<void*>(key));
#endif
}

// One call the library makes on the object: receives at entry, publishes at exit.
class HandoverScope {
 public:
  explicit HandoverScope(const void* key) : key_(key) { receive_handover(key_); }
  ~HandoverScope() { publish_handover(key_); }
  HandoverScope(const HandoverScope&) = delete;
  HandoverScope& operator=(const HandoverScope&) = delete;

 private:
  const void* key_;
};

}  // namespace pnp
