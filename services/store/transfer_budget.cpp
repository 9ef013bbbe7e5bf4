#include "services/store/transfer_budget.h"

#include "common/error.h"
#include "services/common/access_control.h"

namespace pnp::services {

namespace {

std::string mib(std::int64_t bytes) {
  return std::to_string(bytes >> 20) + " MiB";
}

}  // namespace

TransferBudget::TransferBudget(std::int64_t max_bytes, std::int64_t max_checkpoint_bytes,
                               std::chrono::milliseconds wait)
    : max_bytes_(max_bytes), wait_(wait) {
  if (max_bytes / 2 < max_checkpoint_bytes) {
    throw_invalid_argument("--max-transfer-mb",
                           "at least twice --max-checkpoint-mb (" + mib(2 * max_checkpoint_bytes) +
                               "): half of it is one principal's share",
                           mib(max_bytes));
  }
}

TransferBudget::Reservation::~Reservation() {
  if (owner_ != nullptr) owner_->release(principal_, bytes_);
}

bool TransferBudget::fits(const std::string& principal, std::int64_t bytes) const {
  if (held_ + bytes > max_bytes_) return false;
  if (principal.empty()) return true;  // no auth policy: callers are not told apart
  const auto it = held_by_.find(principal);
  return (it == held_by_.end() ? 0 : it->second) + bytes <= principal_share();
}

TransferBudget::Reservation TransferBudget::reserve(grpc::ServerContext& context,
                                                    std::string_view rpc, std::int64_t bytes) {
  return reserve(principal_of(context), rpc, bytes, [&context] { return context.IsCancelled(); });
}

TransferBudget::Reservation TransferBudget::reserve(std::string principal, std::string_view rpc,
                                                    std::int64_t bytes,
                                                    const std::function<bool()>& left) {
  std::unique_lock lock(mutex_);
  const auto deadline = std::chrono::steady_clock::now() + wait_;
  // A short step between looks: a caller that leaves while waiting is noticed.
  constexpr auto kStep = std::chrono::milliseconds(100);
  while (!fits(principal, bytes)) {
    if (left()) throw Error(ErrorCode::kCancelled, std::string(rpc) + ": caller left");
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) {
      throw Error(ErrorCode::kResourceExhausted,
                  std::string(rpc) + ": the store server already holds " + mib(held_) + " of " +
                      mib(max_bytes_) +
                      " checkpoint bytes in transfer (--max-transfer-mb; one principal at most "
                      "half); retry when a transfer ends");
    }
    released_.wait_for(lock, std::min<std::chrono::steady_clock::duration>(kStep, deadline - now));
  }
  held_ += bytes;
  if (!principal.empty()) held_by_[principal] += bytes;
  return Reservation(this, std::move(principal), bytes);
}

void TransferBudget::release(const std::string& principal, std::int64_t bytes) {
  {
    std::lock_guard lock(mutex_);
    held_ -= bytes;
    if (!principal.empty() && (held_by_[principal] -= bytes) == 0) held_by_.erase(principal);
  }
  released_.notify_all();
}

std::int64_t TransferBudget::held_bytes() const {
  std::lock_guard lock(mutex_);
  return held_;
}

}  // namespace pnp::services
