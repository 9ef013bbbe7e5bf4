#include "store/retry.h"

#include <algorithm>
#include <condition_variable>
#include <mutex>

namespace pnp::store {
namespace {

// SplitMix64: a well-mixed 64-bit value from (seed, attempt), no state kept.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace

std::chrono::milliseconds retry_backoff(const RetryPolicy& policy, int attempt) {
  const auto doubled = policy.first_backoff.count() << std::min(attempt, 20);
  const auto capped = std::min<std::int64_t>(doubled, policy.max_backoff.count());
  const std::uint64_t draw =
      mix(policy.jitter_seed * std::uint64_t{1000003} + static_cast<std::uint64_t>(attempt));
  const double unit = static_cast<double>(draw >> 11) * 0x1.0p-53;  // uniform in [0, 1)
  return std::chrono::milliseconds(std::max<std::int64_t>(
      1, static_cast<std::int64_t>(static_cast<double>(capped) * (0.5 + 0.5 * unit))));
}

bool sleep_unless_stopped(std::chrono::milliseconds pause, const std::stop_token& stop) {
  std::mutex mutex;
  std::condition_variable_any cv;
  std::unique_lock lock(mutex);
  return !cv.wait_for(lock, stop, pause, [] { return false; }) && !stop.stop_requested();
}

}  // namespace pnp::store
