#pragma once
// FNV-1a 64: the checksum of checkpoint files and of the blobs the store keeps. It
// detects accidental corruption (a flipped bit, a truncation), not tampering.

#include <cstdint>
#include <span>
#include <string>

namespace pnp {

std::uint64_t fnv1a64(std::span<const std::uint8_t> bytes);
std::string fnv1a64_hex(std::span<const std::uint8_t> bytes);  // 16 lowercase hex digits

}  // namespace pnp
