#pragma once
// A value many threads read and one occasionally replaces (the served policy): readers get
// a shared_ptr that keeps their snapshot alive however long they use it, and a replacement
// never waits for them.
//
// A mutex, not std::atomic<std::shared_ptr>: GCC 12's libstdc++ releases the lock inside
// load() with relaxed order, so a reader's access is not ordered before the next store's
// write (a data race in the C++ memory model, which ThreadSanitizer reports; see
// google/sanitizers#1558). The lock is held only to copy or swap the pointer.

#include <memory>
#include <mutex>
#include <utility>

namespace pnp {

template <class T>
class SharedSnapshot {
 public:
  SharedSnapshot() = default;
  explicit SharedSnapshot(std::shared_ptr<const T> value) : value_(std::move(value)) {}
  SharedSnapshot(const SharedSnapshot&) = delete;
  SharedSnapshot& operator=(const SharedSnapshot&) = delete;

  std::shared_ptr<const T> load() const {
    std::lock_guard lock(mutex_);
    return value_;
  }

  void store(std::shared_ptr<const T> value) {
    {
      std::lock_guard lock(mutex_);
      value_.swap(value);
    }
    // `value` now holds the old snapshot: the last reference (and the destructor) goes
    // outside the lock, so readers never wait on it.
  }

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const T> value_;
};

}  // namespace pnp
