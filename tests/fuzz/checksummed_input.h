#pragma once
// A fuzz input as a checkpoint file whose trailing checksum (its last 8 bytes) is
// recomputed: a mutation then reaches the parser's section, size and bounds checks, as a
// crafted file with a valid checksum would, instead of stopping at the checksum.

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "common/checksum.h"

namespace pnp::fuzz {

inline std::vector<std::uint8_t> with_valid_checksum(std::span<const std::uint8_t> input) {
  std::vector<std::uint8_t> file(input.begin(), input.end());
  if (file.size() < sizeof(std::uint64_t)) return file;
  const std::size_t body = file.size() - sizeof(std::uint64_t);
  const std::uint64_t checksum = fnv1a64(std::span(file).first(body));
  std::memcpy(file.data() + body, &checksum, sizeof(checksum));
  return file;
}

}  // namespace pnp::fuzz
