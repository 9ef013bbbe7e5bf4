#include "common/secret_token.h"

#include <sys/random.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstring>

#include "common/error.h"

namespace pnp {

std::string secret_token_hex(int bytes) {
  if (bytes <= 0 || bytes > 64) throw_invalid_argument("bytes", "1 to 64", std::to_string(bytes));
  std::array<std::uint8_t, 64> raw{};
  const auto wanted = static_cast<std::size_t>(bytes);
  std::size_t have = 0;
  while (have < wanted) {
    const ssize_t got = ::getrandom(raw.data() + have, wanted - have, 0);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw_internal(std::string("getrandom: ") + std::strerror(errno));
    }
    have += static_cast<std::size_t>(got);
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * wanted);
  for (std::size_t i = 0; i < wanted; ++i) {
    out.push_back(kHex[raw[i] >> 4]);
    out.push_back(kHex[raw[i] & 0xF]);
  }
  return out;
}

}  // namespace pnp
