#pragma once
// Tells the store service's WatchPromotions streams that the promotions may have changed:
// a version that every promoting call bumps, and a wait for it to move.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace pnp::services {

class PromotionFeed {
 public:
  void bump() {
    {
      std::lock_guard lock(mutex_);
      ++version_;
    }
    changed_.notify_all();
  }
  std::uint64_t version() const {
    std::lock_guard lock(mutex_);
    return version_;
  }
  // The version once it differs from `seen`, or after `timeout` (then possibly `seen`).
  std::uint64_t wait_past(std::uint64_t seen, std::chrono::milliseconds timeout) const {
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, timeout, [&] { return version_ != seen; });
    return version_;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::uint64_t version_ = 0;
};

}  // namespace pnp::services
