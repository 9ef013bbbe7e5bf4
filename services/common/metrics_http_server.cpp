#include "services/common/metrics_http_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <memory>
#include <system_error>

#include "common/error.h"

namespace pnp::services {
namespace {

constexpr std::size_t kMaxRequestBytes = 8192;  // a scrape's request is a few hundred
constexpr std::chrono::seconds kReadTimeout{2};
constexpr std::chrono::seconds kWriteTimeout{5};
constexpr std::chrono::milliseconds kLingerTimeout{500};

std::string errno_text(int error) {
  return std::generic_category().message(error);
}

struct HostPort {
  std::string host;  // empty: every interface
  std::string port;
};

HostPort split_address(const std::string& address) {
  const auto colon = address.rfind(':');
  const auto refuse = [&] {
    throw_invalid_argument("metrics address", "host:port with a port in [0, 65535]",
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

// Listening, non-blocking: accept() never blocks on a client that already left.
UniqueFd listen_on(const std::string& address) {
  const HostPort where = split_address(address);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(where.host.empty() ? nullptr : where.host.c_str(),
                                   where.port.c_str(), &hints, &found);
      rc != 0) {
    throw Error(ErrorCode::kUnavailable,
                "metrics: cannot listen on " + address + ": " + ::gai_strerror(rc));
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
              "metrics: cannot listen on " + address + ": " + errno_text(error));
}

std::string response(std::string_view status, std::string_view content_type, std::string_view body,
                     std::string_view extra_headers = {}) {
  std::string out;
  out.append("HTTP/1.1 ").append(status).append("\r\n");
  out.append("Content-Type: ").append(content_type).append("\r\n");
  out.append("Content-Length: ").append(std::to_string(body.size())).append("\r\n");
  out.append(extra_headers);
  out.append("Connection: close\r\n\r\n").append(body);
  return out;
}

std::string plain(std::string_view status, std::string_view extra_headers = {}) {
  return response(status, "text/plain; charset=utf-8", std::string(status) + "\n", extra_headers);
}

}  // namespace

MetricsHttpServer::MetricsHttpServer(const std::string& address, const MetricsRegistry& registry)
    : registry_(registry), listener_(listen_on(address)) {
  port_ = bound_port(listener_.get());
  std::array<int, 2> pipe_fds{};
  if (::pipe2(pipe_fds.data(), O_CLOEXEC | O_NONBLOCK) != 0)
    throw Error(ErrorCode::kUnavailable, "metrics: cannot create a pipe: " + errno_text(errno));
  wake_read_ = UniqueFd(pipe_fds[0]);
  wake_write_ = UniqueFd(pipe_fds[1]);
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

MetricsHttpServer::~MetricsHttpServer() {
  thread_.request_stop();
  const char byte = 0;  // the pipe stays readable: a poll that starts later wakes too
  const auto written = ::write(wake_write_.get(), &byte, 1);
  static_cast<void>(written);
  // thread_ joins as it is destroyed, before the descriptors close.
}

void MetricsHttpServer::run(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    std::array<pollfd, 2> fds{{{listener_.get(), POLLIN, 0}, {wake_read_.get(), POLLIN, 0}}};
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[1].revents != 0) return;
    if ((fds[0].revents & POLLIN) == 0) continue;
    const UniqueFd client(
        ::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK));
    if (client.valid()) {
      serve(client.get());
    } else if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
      // Out of descriptors or memory: back off instead of spinning on the ready listener.
      wait_for(-1, 0, std::chrono::steady_clock::now() + std::chrono::milliseconds(100));
    }
  }
}

bool MetricsHttpServer::wait_for(int fd, short events,
                                 std::chrono::steady_clock::time_point deadline) const {
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    std::array<pollfd, 2> fds{{{fd, events, 0}, {wake_read_.get(), POLLIN, 0}}};
    const int ready = ::poll(fds.data(), fds.size(), static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0 || fds[1].revents != 0) return false;
    return fds[0].revents != 0;  // ready, or an error the next call reports
  }
}

void MetricsHttpServer::serve(int client) const {
  // Read the request head (request line and headers) within the cap and the deadline.
  std::string request;
  const auto read_deadline = std::chrono::steady_clock::now() + kReadTimeout;
  std::string answer;
  while (answer.empty() && request.find("\r\n\r\n") == std::string::npos) {
    if (request.size() > kMaxRequestBytes) {
      answer = plain("431 Request Header Fields Too Large");
      break;
    }
    if (!wait_for(client, POLLIN, read_deadline)) return;
    std::array<char, 2048> buffer{};
    const auto n = ::recv(client, buffer.data(), buffer.size(), 0);
    if (n == 0) return;  // the client left
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
      return;
    }
    request.append(buffer.data(), static_cast<std::size_t>(n));
  }

  if (answer.empty()) {
    // "METHOD SP target SP HTTP/1.x"
    const std::string_view line = std::string_view(request).substr(0, request.find("\r\n"));
    const auto first_space = line.find(' ');
    const auto second_space = line.find(' ', first_space == line.npos ? 0 : first_space + 1);
    if (first_space == line.npos || second_space == line.npos ||
        !line.substr(second_space + 1).starts_with("HTTP/1.")) {
      answer = plain("400 Bad Request");
    } else {
      const std::string_view method = line.substr(0, first_space);
      std::string_view target = line.substr(first_space + 1, second_space - first_space - 1);
      target = target.substr(0, target.find('?'));
      if (method != "GET") {
        answer = plain("405 Method Not Allowed", "Allow: GET\r\n");
      } else if (target != "/metrics") {
        answer = plain("404 Not Found");
      } else {
        answer = response("200 OK", "text/plain; version=0.0.4; charset=utf-8", registry_.render());
      }
    }
  }

  const auto write_deadline = std::chrono::steady_clock::now() + kWriteTimeout;
  std::size_t sent = 0;
  while (sent < answer.size()) {
    if (!wait_for(client, POLLOUT, write_deadline)) return;
    const auto n = ::send(client, answer.data() + sent, answer.size() - sent, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
      return;
    }
    sent += static_cast<std::size_t>(n);
  }
  // Half-close, then read what the client still sends until it closes: closing with
  // unread input would reset the connection and could cut the answer short.
  ::shutdown(client, SHUT_WR);
  const auto linger_deadline = std::chrono::steady_clock::now() + kLingerTimeout;
  std::array<char, 2048> buffer{};
  for (std::size_t drained = 0; drained <= kMaxRequestBytes;) {
    if (!wait_for(client, POLLIN, linger_deadline)) return;
    const auto n = ::recv(client, buffer.data(), buffer.size(), 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) return;
    if (n > 0) drained += static_cast<std::size_t>(n);
  }
}

}  // namespace pnp::services
