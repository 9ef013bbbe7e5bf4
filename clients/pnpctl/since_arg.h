#pragma once
// A point in time as users type it for --since: how long ago ("90s", "15m", "2h", "7d") or
// a UTC date or time ("2026-12-04", "2026-12-04T15:30", "2026-12-04T15:30:00Z").

#include <cstdint>
#include <string>

namespace pnp::pnpctl {

// Milliseconds since the epoch; INVALID_ARGUMENT naming `flag` for anything else.
std::int64_t parse_since(const std::string& text, std::int64_t now_ms, const std::string& flag);

// "2026-12-04T15:30:00.123Z"
std::string utc_text(std::int64_t ms);

}  // namespace pnp::pnpctl
