#include "tests/integration/metrics_scrape.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>

namespace pnp::integration {

// GET http://127.0.0.1:port/path, the whole response (headers included).
int connect_loopback(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  sockaddr generic{};
  static_assert(sizeof address >= sizeof generic);
  std::memcpy(&generic, &address, sizeof generic);
  if (::connect(fd, &generic, sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

std::string http_get(int port, const std::string& path) {
  struct Socket {
    int fd;
    ~Socket() {
      if (fd >= 0) ::close(fd);
    }
  } socket{connect_loopback(port)};
  if (socket.fd < 0) return {};
  // A server that stalls fails the test instead of hanging it.
  timeval patience{30, 0};
  ::setsockopt(socket.fd, SOL_SOCKET, SO_RCVTIMEO, &patience, sizeof patience);
  const std::string request = "GET " + path + " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
  if (::send(socket.fd, request.data(), request.size(), 0) != static_cast<ssize_t>(request.size()))
    return {};
  std::string response;
  std::array<char, 4096> buffer{};
  for (;;) {
    const ssize_t got = ::recv(socket.fd, buffer.data(), buffer.size(), 0);
    if (got <= 0) break;
    response.append(buffer.data(), static_cast<std::size_t>(got));
  }
  return response;
}

// The sum of a Prometheus family's samples whose labels include every one of `labels`.
double metric_sum(const std::string& exposition, const std::string& family,
                  const std::vector<std::string>& labels) {
  double sum = 0;
  std::istringstream lines(exposition);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(family + "{", 0) != 0 && line.rfind(family + " ", 0) != 0) continue;
    bool all = true;
    for (const auto& label : labels) all = all && line.find(label) != std::string::npos;
    if (all) sum += std::stod(line.substr(line.rfind(' ') + 1));
  }
  return sum;
}

// The "metrics_port" of a server's "listening" log line (stderr's first).
int metrics_port(const ChildProcess& server) {
  const std::string err = server.stderr_text();
  const auto listening = nlohmann::json::parse(err.substr(0, err.find('\n')), nullptr, false);
  if (listening.is_discarded() || !listening.contains("metrics_port")) return 0;
  return listening.at("metrics_port").get<int>();
}

}  // namespace pnp::integration
