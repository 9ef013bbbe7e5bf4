#pragma once
// The check every command-line seed flag takes: a seed is an integer from 0 to 2^64 - 1,
// written in decimal. CLI11 alone would wrap "-1" to 18446744073709551615 and clamp
// "99999999999999999999" to the same, so two different mistakes would silently run as one
// valid seed.
//
//   app.add_option("--seed", seed)->check(pnp::seed_value());

#include <CLI/CLI.hpp>
#include <charconv>
#include <cstdint>
#include <string>

namespace pnp {

inline CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, value);
        if (text.empty() || text.front() == '+' || error != std::errc() || stop != end)
          return "expected an integer from 0 to 18446744073709551615, got \"" + text + "\"";
        return {};
      },
      "SEED");
}

}  // namespace pnp
