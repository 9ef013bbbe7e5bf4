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
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "common/error.h"
#include "services/common/tcp_listener.h"

namespace pnp::services {
namespace {

constexpr std::size_t kMaxRequestBytes = 8192;  // a scrape's request is a few hundred
using Clock = std::chrono::steady_clock;

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

struct MetricsHttpServer::Connection {
  enum class Phase { kReading, kWriting, kLingering };
  UniqueFd fd;
  std::string peer;
  Phase phase = Phase::kReading;
  std::string in;   // the request head so far
  std::string out;  // the answer
  std::size_t sent = 0;
  std::size_t drained = 0;
  Clock::time_point deadline;
};

MetricsHttpServer::MetricsHttpServer(const std::string& address, const MetricsRegistry& registry,
                                     MetricsHttpLimits limits)
    : registry_(registry), limits_(limits), listener_(listen_on(address, "metrics")) {
  if (limits_.max_connections <= 0 || limits_.max_connections_per_peer <= 0)
    throw_invalid_argument("metrics limits", "positive connection caps",
                           std::to_string(limits_.max_connections) + ", " +
                               std::to_string(limits_.max_connections_per_peer));
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
  std::vector<Connection> open;
  std::vector<pollfd> fds;
  while (!stop.stop_requested()) {
    // The listener only while a slot is free: a full server leaves new clients queued.
    fds.clear();
    const bool room = static_cast<int>(open.size()) < limits_.max_connections;
    fds.push_back({wake_read_.get(), POLLIN, 0});
    fds.push_back({room ? listener_.get() : -1, POLLIN, 0});
    auto next_deadline = Clock::time_point::max();
    for (const Connection& c : open) {
      const short events = c.phase == Connection::Phase::kWriting ? POLLOUT : POLLIN;
      fds.push_back({c.fd.get(), events, 0});
      next_deadline = std::min(next_deadline, c.deadline);
    }
    int timeout_ms = -1;
    if (next_deadline != Clock::time_point::max()) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(next_deadline - Clock::now());
      timeout_ms = static_cast<int>(std::clamp<long long>(left.count() + 1, 0, 60'000));
    }
    if (::poll(fds.data(), fds.size(), timeout_ms) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[0].revents != 0) return;
    // Connections first (their pollfds follow the two fixed ones), then new clients.
    const auto now = Clock::now();
    std::vector<Connection> still_open;
    still_open.reserve(open.size());
    for (std::size_t k = 0; k < open.size(); ++k) {
      Connection& c = open[k];
      const bool keep = fds[k + 2].revents != 0 ? advance(c) : true;
      // Past its deadline (advance() sets a new one when the phase changes): closed.
      if (keep && now < c.deadline) still_open.push_back(std::move(c));
    }
    open = std::move(still_open);
    if ((fds[1].revents & POLLIN) != 0) accept_all(open);
  }
}

void MetricsHttpServer::accept_all(std::vector<Connection>& open) const {
  while (static_cast<int>(open.size()) < limits_.max_connections) {
    sockaddr_storage storage{};
    socklen_t length = sizeof storage;
    UniqueFd client(::accept4(listener_.get(), reinterpret_cast<sockaddr*>(&storage), &length,
                              SOCK_CLOEXEC | SOCK_NONBLOCK));
    if (!client.valid()) {
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        // Out of descriptors or memory: let the open connections finish first.
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      return;  // EAGAIN: none left to accept
    }
    std::string peer = peer_of(storage);
    const auto same_peer = std::count_if(open.begin(), open.end(),
                                         [&](const Connection& c) { return c.peer == peer; });
    if (same_peer >= limits_.max_connections_per_peer) continue;  // closed at once
    Connection c;
    c.fd = std::move(client);
    c.peer = std::move(peer);
    c.deadline = Clock::now() + limits_.header_deadline;
    open.push_back(std::move(c));
  }
}

bool MetricsHttpServer::advance(Connection& c) const {
  std::array<char, 2048> buffer{};
  switch (c.phase) {
    case Connection::Phase::kReading: {
      const auto n = ::recv(c.fd.get(), buffer.data(), buffer.size(), 0);
      if (n == 0) return false;  // the client left
      if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
      c.in.append(buffer.data(), static_cast<std::size_t>(n));
      if (c.in.size() > kMaxRequestBytes) {
        c.out = plain("431 Request Header Fields Too Large");
      } else if (c.in.find("\r\n\r\n") != std::string::npos) {
        c.out = answer(c.in);
      } else {
        return true;  // more to come, within the header deadline
      }
      c.phase = Connection::Phase::kWriting;
      c.deadline = Clock::now() + limits_.write_deadline;
      return true;
    }
    case Connection::Phase::kWriting: {
      const auto n = ::send(c.fd.get(), c.out.data() + c.sent, c.out.size() - c.sent, MSG_NOSIGNAL);
      if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
      c.sent += static_cast<std::size_t>(n);
      if (c.sent < c.out.size()) return true;
      // Half-close, then read what the client still sends until it closes: closing with
      // unread input would reset the connection and could cut the answer short.
      ::shutdown(c.fd.get(), SHUT_WR);
      c.phase = Connection::Phase::kLingering;
      c.deadline = Clock::now() + limits_.linger;
      return true;
    }
    case Connection::Phase::kLingering: {
      const auto n = ::recv(c.fd.get(), buffer.data(), buffer.size(), 0);
      if (n == 0) return false;
      if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
      c.drained += static_cast<std::size_t>(n);
      return c.drained <= kMaxRequestBytes;
    }
  }
  return false;
}

std::string MetricsHttpServer::answer(const std::string& request) const {
  // "METHOD SP target SP HTTP/1.x"
  const std::string_view line = std::string_view(request).substr(0, request.find("\r\n"));
  const auto first_space = line.find(' ');
  const auto second_space = line.find(' ', first_space == line.npos ? 0 : first_space + 1);
  if (first_space == line.npos || second_space == line.npos ||
      !line.substr(second_space + 1).starts_with("HTTP/1.")) {
    return plain("400 Bad Request");
  }
  const std::string_view method = line.substr(0, first_space);
  std::string_view target = line.substr(first_space + 1, second_space - first_space - 1);
  target = target.substr(0, target.find('?'));
  if (method != "GET") return plain("405 Method Not Allowed", "Allow: GET\r\n");
  if (target != "/metrics") return plain("404 Not Found");
  return response("200 OK", "text/plain; version=0.0.4; charset=utf-8", registry_.render());
}

}  // namespace pnp::services
