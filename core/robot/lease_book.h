#pragma once
// Who may drive the arm: at most one lease at a time, as a real arm's controller grants
// (Boston Dynamics' lease, Viam's session). A lease lasts `timeout` after its last
// renewal; every pose target renews it. An expired lease is as good as released: the
// next client may take one, and the old holder's commands are refused from then on.
// Time is passed in, so tests need no clock.

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace pnp::robot {

class LeaseBook {
 public:
  using Clock = std::chrono::steady_clock;

  // INVALID_ARGUMENT for an empty client name or a non-positive timeout.
  // FAILED_PRECONDITION naming the holder while another unexpired lease exists.
  std::string acquire(const std::string& client, Clock::duration timeout, Clock::time_point now);
  // Whether `lease_id` is the current, unexpired lease; if so it is renewed.
  bool renew(const std::string& lease_id, Clock::time_point now);
  bool valid(const std::string& lease_id, Clock::time_point now) const;
  // NOT_FOUND unless `lease_id` is the current lease (expired or not).
  void release(const std::string& lease_id);

  // The holder's name, or nullopt when nobody holds an unexpired lease.
  std::optional<std::string> holder(Clock::time_point now) const;

 private:
  struct Lease {
    std::string id, client;
    Clock::duration timeout{};
    Clock::time_point expires;
  };
  std::optional<Lease> current_;
};

}  // namespace pnp::robot
