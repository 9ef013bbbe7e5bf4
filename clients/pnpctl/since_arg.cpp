#include "clients/pnpctl/since_arg.h"

#include <cstdio>
#include <ctime>

#include "common/error.h"

namespace pnp::pnpctl {
namespace {

constexpr const char* kExpected =
    "a duration ago (90s, 15m, 2h, 7d) or a UTC time (2026-12-04, 2026-12-04T15:30[:00][Z])";

std::int64_t ago(const std::string& text, std::int64_t now_ms, const std::string& flag) {
  const char unit = text.back();
  const std::string digits = text.substr(0, text.size() - 1);
  std::int64_t unit_ms = 0;
  switch (unit) {
    case 's':
      unit_ms = 1000;
      break;
    case 'm':
      unit_ms = 60'000;
      break;
    case 'h':
      unit_ms = 3'600'000;
      break;
    case 'd':
      unit_ms = 86'400'000;
      break;
    default:
      throw_invalid_argument(flag, kExpected, "\"" + text + "\"");
  }
  if (digits.empty() || digits.size() > 9 ||
      digits.find_first_not_of("0123456789") != std::string::npos)
    throw_invalid_argument(flag, kExpected, "\"" + text + "\"");
  return now_ms - std::stoll(digits) * unit_ms;
}

std::int64_t utc(const std::string& text, const std::string& flag) {
  std::tm tm{};
  int consumed = 0;
  const char* s = text.c_str();
  if (std::sscanf(s, "%4d-%2d-%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &consumed) != 3)
    throw_invalid_argument(flag, kExpected, "\"" + text + "\"");
  std::string rest = text.substr(static_cast<std::size_t>(consumed));
  if (!rest.empty()) {
    int used = 0;
    if (std::sscanf(rest.c_str(), "T%2d:%2d%n", &tm.tm_hour, &tm.tm_min, &used) != 2)
      throw_invalid_argument(flag, kExpected, "\"" + text + "\"");
    rest = rest.substr(static_cast<std::size_t>(used));
    if (!rest.empty() && rest[0] == ':') {
      if (std::sscanf(rest.c_str(), ":%2d%n", &tm.tm_sec, &used) != 1)
        throw_invalid_argument(flag, kExpected, "\"" + text + "\"");
      rest = rest.substr(static_cast<std::size_t>(used));
    }
    if (rest == "Z") rest.clear();
  }
  if (!rest.empty() || tm.tm_mon < 1 || tm.tm_mon > 12 || tm.tm_mday < 1 || tm.tm_mday > 31 ||
      tm.tm_hour > 23 || tm.tm_min > 59 || tm.tm_sec > 60)
    throw_invalid_argument(flag, kExpected, "\"" + text + "\"");
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<std::int64_t>(timegm(&tm)) * 1000;
}

}  // namespace

std::int64_t parse_since(const std::string& text, std::int64_t now_ms, const std::string& flag) {
  if (text.empty()) throw_invalid_argument(flag, kExpected, "\"\"");
  if (text.find('-') != std::string::npos) return utc(text, flag);
  return ago(text, now_ms, flag);
}

std::string utc_text(std::int64_t ms) {
  const std::time_t seconds = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[80];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>(ms % 1000));
  return text;
}

}  // namespace pnp::pnpctl
