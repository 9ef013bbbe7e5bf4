#include "clients/dashboard/session_book.h"

#include <algorithm>

#include "common/secret_token.h"

namespace pnp::dashboard {
namespace {

// Drops the entry that expires first when `entries` is full.
template <typename Map, typename Expiry>
void make_room(Map& entries, std::size_t limit, Expiry expiry) {
  if (entries.size() < limit) return;
  const auto oldest = std::min_element(
      entries.begin(), entries.end(),
      [&](const auto& a, const auto& b) { return expiry(a.second) < expiry(b.second); });
  entries.erase(oldest);
}

}  // namespace

SessionBook::SessionBook(std::chrono::seconds lifetime, std::function<Clock::time_point()> now)
    : lifetime_(lifetime), now_(std::move(now)) {}

std::string SessionBook::open(const std::string& principal) {
  std::string id = secret_token_hex(32);
  std::lock_guard lock(mutex_);
  const auto now = now_();
  sweep(now);
  make_room(sessions_, kMaxSessions, [](const Session& s) { return s.expires; });
  sessions_[id] = {principal, now + lifetime_};
  return id;
}

std::optional<std::string> SessionBook::principal(const std::string& id) {
  std::lock_guard lock(mutex_);
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return std::nullopt;
  if (now_() >= it->second.expires) {
    sessions_.erase(it);
    return std::nullopt;
  }
  return it->second.principal;
}

void SessionBook::close(const std::string& id) {
  std::lock_guard lock(mutex_);
  sessions_.erase(id);
}

std::string SessionBook::issue_login_nonce() {
  std::string nonce = secret_token_hex(16);
  std::lock_guard lock(mutex_);
  const auto now = now_();
  sweep(now);
  make_room(login_nonces_, kMaxLoginForms, [](Clock::time_point t) { return t; });
  login_nonces_[nonce] = now + kLoginFormLifetime;
  return nonce;
}

bool SessionBook::redeem_login_nonce(const std::string& nonce) {
  std::lock_guard lock(mutex_);
  const auto it = login_nonces_.find(nonce);
  if (it == login_nonces_.end()) return false;
  const bool live = now_() < it->second;
  login_nonces_.erase(it);  // once only
  return live;
}

std::size_t SessionBook::sessions() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

void SessionBook::sweep(Clock::time_point now) {
  std::erase_if(sessions_, [&](const auto& entry) { return now >= entry.second.expires; });
  std::erase_if(login_nonces_, [&](const auto& entry) { return now >= entry.second; });
}

}  // namespace pnp::dashboard
