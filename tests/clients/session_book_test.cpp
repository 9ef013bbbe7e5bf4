#include "clients/dashboard/session_book.h"

#include <gtest/gtest.h>

#include <set>

namespace pnp::dashboard {
namespace {

using std::chrono::hours;
using std::chrono::seconds;

// A clock the test moves.
struct FakeClock {
  SessionBook::Clock::time_point now{};
  std::function<SessionBook::Clock::time_point()> fn() {
    return [this] { return now; };
  }
};

TEST(SessionBook, ASessionNamesItsPrincipalUntilItExpiresOrIsClosed) {
  FakeClock clock;
  SessionBook book(hours(8), clock.fn());
  const std::string id = book.open("reader");
  EXPECT_EQ(id.size(), 64u);
  EXPECT_EQ(book.principal(id), "reader");
  EXPECT_EQ(book.principal("not-a-session"), std::nullopt);
  clock.now += hours(8) - seconds(1);
  EXPECT_EQ(book.principal(id), "reader");
  clock.now += seconds(1);
  EXPECT_EQ(book.principal(id), std::nullopt) << "expired";
  const std::string other = book.open("reader");
  book.close(other);
  EXPECT_EQ(book.principal(other), std::nullopt) << "signed out";
}

TEST(SessionBook, IdsAreRandomAndNeverRepeat) {
  SessionBook book;
  std::set<std::string> ids;
  for (int k = 0; k < 100; ++k) ids.insert(book.open("reader"));
  EXPECT_EQ(ids.size(), 100u);
}

TEST(SessionBook, ALoginNonceIsRedeemedOnceWithinItsLifetime) {
  FakeClock clock;
  SessionBook book(hours(8), clock.fn());
  const std::string nonce = book.issue_login_nonce();
  EXPECT_TRUE(book.redeem_login_nonce(nonce));
  EXPECT_FALSE(book.redeem_login_nonce(nonce)) << "a replayed form";
  EXPECT_FALSE(book.redeem_login_nonce("forged"));
  const std::string late = book.issue_login_nonce();
  clock.now += SessionBook::kLoginFormLifetime;
  EXPECT_FALSE(book.redeem_login_nonce(late));
}

TEST(SessionBook, ManySignInsCannotGrowItPastItsBound) {
  FakeClock clock;
  SessionBook book(hours(8), clock.fn());
  const std::string first = book.open("reader");
  for (std::size_t k = 0; k < SessionBook::kMaxSessions; ++k) {
    clock.now += std::chrono::milliseconds(60);
    book.open("reader");
  }
  EXPECT_EQ(book.sessions(), SessionBook::kMaxSessions);
  EXPECT_EQ(book.principal(first), std::nullopt) << "the oldest made room";
}

}  // namespace
}  // namespace pnp::dashboard
