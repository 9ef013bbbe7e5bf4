#pragma once
// FNV-1a 64: the checksum of checkpoint files and of the blobs the store keeps. It
// detects accidental corruption (a flipped bit, a truncation), not tampering.

#include <cstdint>
#include <span>
#include <string>

namespace pnp {

inline constexpr std::uint64_t kFnv1a64Start = 0xCBF29CE484222325ULL;

// `from`: the checksum of the bytes that came before these (kFnv1a64Start: none), so a
// stream too long to hold is checksummed piece by piece.
std::uint64_t fnv1a64(std::span<const std::uint8_t> bytes, std::uint64_t from = kFnv1a64Start);
std::string fnv1a64_hex(std::span<const std::uint8_t> bytes);  // 16 lowercase hex digits
std::string checksum_hex(std::uint64_t checksum);              // 16 lowercase hex digits

}  // namespace pnp
