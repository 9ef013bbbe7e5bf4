#include "services/common/address.h"

#include <algorithm>
#include <cctype>

#include "common/error.h"

namespace pnp::services {

void validate_address(std::string_view address, std::string_view field) {
  if (address.starts_with("unix:")) return;  // a Unix socket path: no port
  const auto colon = address.rfind(':');
  const std::string_view host = colon == std::string_view::npos ? "" : address.substr(0, colon);
  const std::string_view port = colon == std::string_view::npos ? "" : address.substr(colon + 1);
  const bool digits =
      !port.empty() && port.size() <= 5 && std::all_of(port.begin(), port.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c));
      });
  if (host.empty() || !digits || std::stoi(std::string(port)) > 65535) {
    throw_invalid_argument(field, "host:port with a port in 0..65535",
                           "\"" + std::string(address) + "\"");
  }
}

}  // namespace pnp::services
