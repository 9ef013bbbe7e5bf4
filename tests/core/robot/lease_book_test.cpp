#include "robot/lease_book.h"

#include <gtest/gtest.h>

#include <optional>
#include <set>
#include <string>

#include "common/error.h"

namespace pnp::robot {
namespace {

using namespace std::chrono_literals;
using Clock = LeaseBook::Clock;

std::optional<ErrorCode> code_of(auto&& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.code();
  }
  return std::nullopt;
}

// A lease id is the capability to drive the arm: 128 random bits as hex, nothing a
// stranger could derive from the holder's name, a counter or the time.
TEST(LeaseBook, IdsAreRandomAndSayNothingOfTheirHolder) {
  LeaseBook book;
  const auto t0 = Clock::time_point{} + 10s;
  std::set<std::string> ids;
  for (int i = 0; i < 50; ++i) {
    const std::string id = book.acquire("gateway-a", 1s, t0);
    EXPECT_EQ(id.size(), 32u);
    EXPECT_EQ(id.find_first_not_of("0123456789abcdef"), std::string::npos) << id;
    EXPECT_EQ(id.find("gateway"), std::string::npos) << id;
    ids.insert(id);
    book.release(id);
  }
  EXPECT_EQ(ids.size(), 50u) << "the same time and name never give the same id";
}

TEST(LeaseBook, OneHolderAtATimeUntilReleased) {
  LeaseBook book;
  const auto t0 = Clock::time_point{} + 10s;
  const std::string first = book.acquire("gateway-a", 1s, t0);
  EXPECT_TRUE(book.valid(first, t0));
  EXPECT_EQ(book.holder(t0), "gateway-a");
  try {
    book.acquire("gateway-b", 1s, t0 + 100ms);
    FAIL() << "a second lease was granted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("\"gateway-a\""), std::string::npos) << e.what();
  }
  book.release(first);
  EXPECT_FALSE(book.valid(first, t0));
  const std::string second = book.acquire("gateway-b", 1s, t0 + 200ms);
  EXPECT_NE(second, first);
  EXPECT_FALSE(book.renew(first, t0 + 300ms));  // the old holder is refused
}

TEST(LeaseBook, RenewalExtendsAndExpiryFreesTheArm) {
  LeaseBook book;
  const auto t0 = Clock::time_point{} + 10s;
  const std::string id = book.acquire("gateway", 100ms, t0);
  EXPECT_TRUE(book.renew(id, t0 + 90ms));
  EXPECT_TRUE(book.valid(id, t0 + 180ms));  // renewed at 90 ms: valid until 190 ms
  EXPECT_FALSE(book.valid(id, t0 + 190ms));
  EXPECT_FALSE(book.renew(id, t0 + 200ms));
  EXPECT_EQ(book.holder(t0 + 200ms), std::nullopt);
  EXPECT_NO_THROW(book.acquire("other", 100ms, t0 + 200ms));
}

TEST(LeaseBook, RefusesBadRequests) {
  LeaseBook book;
  const auto now = Clock::time_point{} + 1s;
  EXPECT_EQ(code_of([&] { book.acquire("", 1s, now); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code_of([&] { book.acquire("g", 0s, now); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(code_of([&] { book.release("nope"); }), ErrorCode::kNotFound);
  EXPECT_FALSE(book.valid("", now));
}

}  // namespace
}  // namespace pnp::robot
