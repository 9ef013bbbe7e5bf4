#include "common/checksum.h"

#include <cstdio>

namespace pnp {

std::uint64_t fnv1a64(std::span<const std::uint8_t> bytes, std::uint64_t from) {
  std::uint64_t h = from;
  for (std::uint8_t b : bytes) {
    h ^= b;
    h *= 0x100000001B3ULL;
  }
  return h;
}

std::string fnv1a64_hex(std::span<const std::uint8_t> bytes) {
  return checksum_hex(fnv1a64(bytes));
}

std::string checksum_hex(std::uint64_t checksum) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(checksum));
  return text;
}

}  // namespace pnp
