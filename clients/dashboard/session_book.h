#pragma once
// Browser sign-ins to the dashboard: the token a reader gives once at /login stays on the
// server; the browser's cookie carries only a session id (256 random bits) that names the
// principal here until it expires or the reader signs out. The login form carries a
// one-time nonce the server issued to that browser (also its cookie), so another site
// cannot sign a browser in under the attacker's token (login CSRF).

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace pnp::dashboard {

class SessionBook {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::hours kDefaultLifetime{8};
  static constexpr std::chrono::minutes kLoginFormLifetime{10};
  // Beyond these, the oldest session (or login form) makes room: many sign-ins cannot
  // grow the server's memory.
  static constexpr std::size_t kMaxSessions = 1024;
  static constexpr std::size_t kMaxLoginForms = 1024;

  explicit SessionBook(std::chrono::seconds lifetime = kDefaultLifetime,
                       std::function<Clock::time_point()> now = Clock::now);

  // A new session of `principal`; returns its id (64 hex digits).
  std::string open(const std::string& principal);
  // The principal of a live session; none for an unknown, closed or expired id.
  std::optional<std::string> principal(const std::string& id);
  void close(const std::string& id);  // sign out; an unknown id is a no-op

  // A nonce for one login form; `redeem` accepts it once, within kLoginFormLifetime.
  std::string issue_login_nonce();
  bool redeem_login_nonce(const std::string& nonce);

  std::chrono::seconds lifetime() const { return lifetime_; }
  std::size_t sessions() const;

 private:
  struct Session {
    std::string principal;
    Clock::time_point expires;
  };
  void sweep(Clock::time_point now);  // under mutex_

  std::chrono::seconds lifetime_;
  std::function<Clock::time_point()> now_;
  mutable std::mutex mutex_;
  std::map<std::string, Session> sessions_;
  std::map<std::string, Clock::time_point> login_nonces_;  // nonce -> expiry
};

}  // namespace pnp::dashboard
