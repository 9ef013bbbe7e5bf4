#include "robot/lease_book.h"

#include "common/error.h"
#include "common/secret_token.h"

namespace pnp::robot {

std::string LeaseBook::acquire(const std::string& client, Clock::duration timeout,
                               Clock::time_point now) {
  if (client.empty()) throw_invalid_argument("client_name", "a non-empty name", "\"\"");
  if (timeout <= Clock::duration::zero()) {
    throw_invalid_argument("timeout", "a positive duration",
                           std::to_string(std::chrono::duration<double>(timeout).count()) + " s");
  }
  if (const auto who = holder(now)) {
    throw Error(
        ErrorCode::kFailedPrecondition,
        "the arm is leased to \"" + *who + "\": wait until it releases the lease or it expires");
  }
  // The id is the capability to drive the arm: 128 random bits, never derived from the
  // name, a counter or the clock (those were guessable), and never logged.
  Lease lease{secret_token_hex(16), client, timeout, now + timeout};
  current_ = std::move(lease);
  return current_->id;
}

bool LeaseBook::valid(const std::string& lease_id, Clock::time_point now) const {
  return current_ && current_->id == lease_id && now < current_->expires;
}

bool LeaseBook::renew(const std::string& lease_id, Clock::time_point now) {
  if (!valid(lease_id, now)) return false;
  current_->expires = now + current_->timeout;
  return true;
}

void LeaseBook::release(const std::string& lease_id) {
  if (!current_ || current_->id != lease_id) {
    throw Error(ErrorCode::kNotFound, "lease_id: no such lease \"" + lease_id + "\"");
  }
  current_.reset();
}

std::optional<std::string> LeaseBook::holder(Clock::time_point now) const {
  if (current_ && now < current_->expires) return current_->client;
  return std::nullopt;
}

}  // namespace pnp::robot
