#pragma once
// Retries a store operation while the database is busy (BusyError: another connection
// holds the write lock past the busy timeout), with exponential backoff and jitter, up to
// a time budget; then the BusyError goes to the caller, who decides what waiting longer
// means (the training worker puts the run back in its queue). Any other error is not
// retried. The operation must be a whole transaction: a BusyError means nothing of it
// was written.

#include <chrono>
#include <cstdint>
#include <stop_token>

#include "store/sqlite.h"

namespace pnp::store {

struct RetryPolicy {
  std::chrono::milliseconds budget{20000};  // give up once this much time has passed
  std::chrono::milliseconds first_backoff{20};
  std::chrono::milliseconds max_backoff{1000};
  // Seeds the jitter, so that two processes that collided do not retry in step; results
  // never depend on it.
  std::uint64_t jitter_seed = 0;
};

// The backoff before attempt `attempt` (0-based) of a policy: first_backoff * 2^attempt
// capped at max_backoff, scaled by a factor in [0.5, 1) drawn from the jitter seed.
std::chrono::milliseconds retry_backoff(const RetryPolicy& policy, int attempt);

// Sleeps for `pause` unless `stop` is requested first; returns false if it was.
bool sleep_unless_stopped(std::chrono::milliseconds pause, const std::stop_token& stop);

template <typename Operation>
auto with_retry(const RetryPolicy& policy, Operation&& operation, const std::stop_token& stop = {})
    -> decltype(operation()) {
  const auto deadline = std::chrono::steady_clock::now() + policy.budget;
  for (int attempt = 0;; ++attempt) {
    try {
      return operation();
    } catch (const BusyError&) {
      const auto pause = retry_backoff(policy, attempt);
      if (std::chrono::steady_clock::now() + pause >= deadline) throw;
      if (!sleep_unless_stopped(pause, stop)) throw;
    }
  }
}

}  // namespace pnp::store
