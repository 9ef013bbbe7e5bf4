// pnpctl audit --since: durations ago and UTC times, and the refusal naming the flag.
#include <gtest/gtest.h>

#include "clients/pnpctl/since_arg.h"
#include "support/refusal.h"

namespace pnp::pnpctl {
namespace {

constexpr std::int64_t kNow = 1'796'400'000'000;  // 2026-12-04T16:00:00Z

TEST(SinceArg, ADurationCountsBackFromNow) {
  EXPECT_EQ(parse_since("90s", kNow, "--since"), kNow - 90'000);
  EXPECT_EQ(parse_since("15m", kNow, "--since"), kNow - 900'000);
  EXPECT_EQ(parse_since("2h", kNow, "--since"), kNow - 7'200'000);
  EXPECT_EQ(parse_since("7d", kNow, "--since"), kNow - 604'800'000);
}

TEST(SinceArg, AUtcDateOrTimeIsThatInstant) {
  EXPECT_EQ(utc_text(parse_since("2026-12-04", kNow, "--since")), "2026-12-04T00:00:00.000Z");
  EXPECT_EQ(utc_text(parse_since("2026-12-04T15:30", kNow, "--since")), "2026-12-04T15:30:00.000Z");
  EXPECT_EQ(utc_text(parse_since("2026-12-04T15:30:07Z", kNow, "--since")),
            "2026-12-04T15:30:07.000Z");
  EXPECT_EQ(utc_text(kNow + 42), "2026-12-04T16:00:00.042Z");
}

TEST(SinceArg, AnythingElseIsRefusedNamingTheFlag) {
  for (const char* bad :
       {"", "yesterday", "15", "m", "-5m", "1.5h", "2026-13-01", "2026-12-04T25:00",
        "2026-12-04 15:30", "2026-12-04T15:30:00+01:00", "9999999999d"}) {
    const std::string message = pnp::testing::refusal([&] { parse_since(bad, kNow, "--since"); });
    EXPECT_NE(message.find("--since: expected a duration ago"), std::string::npos) << bad;
  }
}

}  // namespace
}  // namespace pnp::pnpctl
