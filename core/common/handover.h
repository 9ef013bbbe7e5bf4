#pragma once
// Tells ThreadSanitizer about an ordering it cannot see: an object of ours that an
// uninstrumented library (Debian's gRPC) calls on its own threads and destroys on another.
// The library orders those steps with its own locks and reference counts, invisible to TSan,
// so without these the constructor's writes, each call's reads and the destructor look like
// races. They compile to nothing in other builds.
//
//   last member: HandedOver handed_over_;                  (publishes once the others are
//                                                         built; receives before they go)
//   each call:   const HandoverScope handover(handed_over_);  (sees the constructor; its
//                                         accesses are seen by later calls and the end)

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

// The constructor's and destructor's side, as the owner's last member: members are built
// in order and destroyed in reverse, so it publishes after every other member is built and
// receives before any is destroyed. Its own address is the key (it reads no member before
// receiving). Not copyable, so neither is its owner.
class HandedOver {
 public:
  HandedOver() { publish_handover(this); }
  ~HandedOver() { receive_handover(this); }
  HandedOver(const HandedOver&) = delete;
  HandedOver& operator=(const HandedOver&) = delete;
};

// One call the library makes on the object: receives at entry, publishes at exit.
class HandoverScope {
 public:
  explicit HandoverScope(const HandedOver& object) : key_(&object) { receive_handover(key_); }
  ~HandoverScope() { publish_handover(key_); }
  HandoverScope(const HandoverScope&) = delete;
  HandoverScope& operator=(const HandoverScope&) = delete;

 private:
  const void* key_;
};

}  // namespace pnp
