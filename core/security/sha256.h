#pragma once
// SHA-256 (FIPS 180-4): how the authorization policy stores bearer tokens, so the policy
// file never holds a usable secret. Written here, checked against the standard's vectors.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace pnp::security {

using Sha256Digest = std::array<std::uint8_t, 32>;

Sha256Digest sha256(std::string_view bytes);
std::string sha256_hex(std::string_view bytes);  // 64 lowercase hex digits

// Compares in time that depends on the length only, never on where the first difference is.
bool constant_time_equal(std::string_view a, std::string_view b);

}  // namespace pnp::security
