#pragma once
// How many checkpoint bytes the store server holds in memory for transfers at once: every
// SaveCheckpoint, LoadCheckpoint and import holds one whole checkpoint (it is checked, or
// read from SQLite, in one piece), so without a bound 64 streams of 64 MiB each would take
// 4 GiB from a Pod limited to 1 GiB. A transfer reserves its checkpoint's size first and
// waits, up to a deadline, for room; one principal holds at most half the budget, so a
// trainer that dribbles its uploads cannot keep the others from saving.
//
//   auto held = budget.reserve(*context, "SaveCheckpoint", header.size_bytes());
//   ... receive, check, store ...        // released when `held` goes

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace pnp::services {

class TransferBudget {
 public:
  // INVALID_ARGUMENT naming --max-transfer-mb unless a principal's share (half) holds the
  // largest checkpoint taken.
  TransferBudget(std::int64_t max_bytes, std::int64_t max_checkpoint_bytes,
                 std::chrono::milliseconds wait = std::chrono::seconds(30));
  TransferBudget(const TransferBudget&) = delete;
  TransferBudget& operator=(const TransferBudget&) = delete;

  class Reservation {
   public:
    Reservation(Reservation&& other) noexcept
        : owner_(other.owner_), principal_(std::move(other.principal_)), bytes_(other.bytes_) {
      other.owner_ = nullptr;
    }
    Reservation(const Reservation&) = delete;
    Reservation& operator=(const Reservation&) = delete;
    Reservation& operator=(Reservation&&) = delete;
    ~Reservation();

   private:
    friend class TransferBudget;
    Reservation(TransferBudget* owner, std::string principal, std::int64_t bytes)
        : owner_(owner), principal_(std::move(principal)), bytes_(bytes) {}
    TransferBudget* owner_;
    std::string principal_;
    std::int64_t bytes_;
  };

  // Waits until `bytes` fit in the budget and in the caller's share, or throws
  // RESOURCE_EXHAUSTED naming the flag (after the wait, or at once if they never could), or
  // CANCELLED if the caller leaves meanwhile.
  Reservation reserve(grpc::ServerContext& context, std::string_view rpc, std::int64_t bytes);
  // The same for `principal` (empty: callers not told apart); `left()` says the caller left.
  Reservation reserve(std::string principal, std::string_view rpc, std::int64_t bytes,
                      const std::function<bool()>& left);

  std::int64_t held_bytes() const;
  std::int64_t max_bytes() const { return max_bytes_; }
  std::int64_t principal_share() const { return max_bytes_ / 2; }

 private:
  bool fits(const std::string& principal, std::int64_t bytes) const;  // under mutex_
  void release(const std::string& principal, std::int64_t bytes);

  std::int64_t max_bytes_;
  std::chrono::milliseconds wait_;
  mutable std::mutex mutex_;
  std::condition_variable released_;
  std::int64_t held_ = 0;
  std::map<std::string, std::int64_t> held_by_;  // per authenticated principal
};

}  // namespace pnp::services
