#include "services/common/tcp_listener.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <memory>
#include <system_error>

#include "common/error.h"

namespace pnp::services {

std::string errno_text(int error) {
  return std::generic_category().message(error);
}

namespace {

struct HostPort {
  std::string host;  // empty: every interface
  std::string port;
};

HostPort split_address(const std::string& address, const std::string& what) {
  const auto colon = address.rfind(':');
  const auto refuse = [&] {
    throw_invalid_argument(what + " address", "host:port with a port in [0, 65535]",
                           "\"" + address + "\"");
  };
  if (colon == std::string::npos) refuse();
  HostPort out{address.substr(0, colon), address.substr(colon + 1)};
  if (out.host.size() >= 2 && out.host.front() == '[' && out.host.back() == ']')
    out.host = out.host.substr(1, out.host.size() - 2);
  if (out.port.empty() || out.port.size() > 5 ||
      !std::all_of(out.port.begin(), out.port.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      std::stoi(out.port) > 65535)
    refuse();
  return out;
}

}  // namespace

UniqueFd listen_on(const std::string& address, const std::string& what) {
  const HostPort where = split_address(address, what);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(where.host.empty() ? nullptr : where.host.c_str(),
                                   where.port.c_str(), &hints, &found);
      rc != 0) {
    throw Error(ErrorCode::kUnavailable,
                what + ": cannot listen on " + address + ": " + ::gai_strerror(rc));
  }
  const std::unique_ptr<addrinfo, decltype(&::freeaddrinfo)> owned(found, &::freeaddrinfo);
  int error = 0;
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    UniqueFd fd(
        ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol));
    if (!fd.valid()) {
      error = errno;
      continue;
    }
    const int on = 1;
    ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (::bind(fd.get(), a->ai_addr, a->ai_addrlen) == 0 && ::listen(fd.get(), 16) == 0) return fd;
    error = errno;
  }
  throw Error(ErrorCode::kUnavailable,
              what + ": cannot listen on " + address + ": " + errno_text(error));
}

std::string peer_of(const sockaddr_storage& storage) {
  std::array<char, INET6_ADDRSTRLEN> text{};
  const void* address =
      storage.ss_family == AF_INET6
          ? static_cast<const void*>(&reinterpret_cast<const sockaddr_in6*>(&storage)->sin6_addr)
          : static_cast<const void*>(&reinterpret_cast<const sockaddr_in*>(&storage)->sin_addr);
  if (::inet_ntop(storage.ss_family, address, text.data(), text.size()) == nullptr) return "?";
  return text.data();
}

int bound_port(int fd) {
  sockaddr_storage storage{};
  socklen_t length = sizeof storage;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&storage), &length) != 0) return 0;
  if (storage.ss_family == AF_INET)
    return ntohs(reinterpret_cast<const sockaddr_in*>(&storage)->sin_port);
  if (storage.ss_family == AF_INET6)
    return ntohs(reinterpret_cast<const sockaddr_in6*>(&storage)->sin6_port);
  return 0;
}

}  // namespace pnp::services
