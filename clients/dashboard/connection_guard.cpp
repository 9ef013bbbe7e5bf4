#include "clients/dashboard/connection_guard.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "common/error.h"
#include "services/common/tcp_listener.h"

namespace pnp::dashboard {
namespace {

using Clock = std::chrono::steady_clock;
using services::UniqueFd;

constexpr std::size_t kRelayBuffer = 64 * 1024;  // per direction: reading pauses when full

UniqueFd connect_backend(int port) {
  UniqueFd fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
  if (!fd.valid()) return fd;
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  // Loopback: the connection is made (or refused) at once.
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&to), sizeof to) != 0) return {};
  ::fcntl(fd.get(), F_SETFL, ::fcntl(fd.get(), F_GETFL) | O_NONBLOCK);
  return fd;
}

enum class Pulled { kOpen, kEnded, kFailed };

// Moves what `from` has into `buffer` (up to kRelayBuffer).
Pulled pull(int from, std::string& buffer) {
  std::array<char, 16 * 1024> chunk{};
  while (buffer.size() < kRelayBuffer) {
    const auto n =
        ::recv(from, chunk.data(), std::min(chunk.size(), kRelayBuffer - buffer.size()), 0);
    if (n > 0) {
      buffer.append(chunk.data(), static_cast<std::size_t>(n));
      continue;
    }
    if (n == 0) return Pulled::kEnded;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return Pulled::kOpen;
    if (errno != EINTR) return Pulled::kFailed;
  }
  return Pulled::kOpen;
}

// Sends what it can of `buffer` to `to`; false on an error.
bool push(int to, std::string& buffer) {
  while (!buffer.empty()) {
    const auto n = ::send(to, buffer.data(), buffer.size(), MSG_NOSIGNAL);
    if (n > 0) {
      buffer.erase(0, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n < 0 && errno == EINTR) continue;
    return false;
  }
  return true;
}

}  // namespace

struct ConnectionGuard::Relay {
  UniqueFd client, backend;
  std::string peer;
  std::string to_backend, to_client;
  bool client_done = false;    // the client closed its side: its answer may still come
  bool client_failed = false;  // the client is gone: nothing more can reach it
  bool backend_done = false;   // httplib closed its side (or failed)
  bool backend_told = false;   // httplib was told the client closed its side
  // Set when the client has sent bytes the backend has not answered yet.
  std::optional<Clock::time_point> awaiting_since;

  // Whether the relay has nothing left to do.
  bool finished() const { return client_failed || (backend_done && to_client.empty()); }
};

ConnectionGuard::ConnectionGuard(const std::string& address, int backend_port, GuardLimits limits)
    : backend_port_(backend_port),
      limits_(limits),
      listener_(services::listen_on(address, "dashboard")) {
  if (limits_.max_connections < 1 || limits_.max_per_peer < 1 ||
      limits_.answer_deadline <= std::chrono::milliseconds(0))
    throw_invalid_argument("guard limits", "positive caps and deadline", "a zero or negative one");
  port_ = services::bound_port(listener_.get());
  std::array<int, 2> pipe_fds{};
  if (::pipe2(pipe_fds.data(), O_CLOEXEC | O_NONBLOCK) != 0)
    throw Error(ErrorCode::kUnavailable,
                "dashboard: cannot create a pipe: " + services::errno_text(errno));
  wake_read_ = UniqueFd(pipe_fds[0]);
  wake_write_ = UniqueFd(pipe_fds[1]);
  thread_ = std::jthread([this](std::stop_token stop) { run(stop); });
}

ConnectionGuard::~ConnectionGuard() {
  thread_.request_stop();
  const char byte = 0;
  [[maybe_unused]] const auto written = ::write(wake_write_.get(), &byte, 1);
  if (thread_.joinable()) thread_.join();
}

void ConnectionGuard::run(const std::stop_token& stop) {
  std::vector<std::unique_ptr<Relay>> relays;
  std::map<std::string, int> per_peer;
  std::vector<pollfd> fds;
  // Closes the relays that are done, and those whose request went unanswered past its
  // deadline (a head that never ends).
  const auto reap = [&](Clock::time_point now) {
    std::erase_if(relays, [&](const std::unique_ptr<Relay>& r) {
      const bool late = r->awaiting_since && now - *r->awaiting_since > limits_.answer_deadline;
      if (!late && !r->finished()) return false;
      if (--per_peer[r->peer] == 0) per_peer.erase(r->peer);
      return true;
    });
  };
  while (!stop.stop_requested()) {
    const auto now = Clock::now();
    reap(now);
    fds.clear();
    fds.push_back({wake_read_.get(), POLLIN, 0});
    fds.push_back({listener_.get(), POLLIN, 0});
    for (const auto& r : relays) {
      short client_events = 0, backend_events = 0;
      if (!r->client_done && r->to_backend.size() < kRelayBuffer) client_events |= POLLIN;
      if (!r->to_client.empty()) client_events |= POLLOUT;
      if (!r->backend_done && r->to_client.size() < kRelayBuffer) backend_events |= POLLIN;
      if (!r->to_backend.empty()) backend_events |= POLLOUT;
      // A closed side with nothing to send is left out (-1): its hang-up would wake poll()
      // again and again.
      fds.push_back({client_events != 0 ? r->client.get() : -1, client_events, 0});
      fds.push_back({backend_events != 0 ? r->backend.get() : -1, backend_events, 0});
    }
    // Wake for the nearest deadline, at the latest in a second.
    auto wait = std::chrono::milliseconds(1000);
    for (const auto& r : relays) {
      if (!r->awaiting_since) continue;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          *r->awaiting_since + limits_.answer_deadline - now);
      wait = std::clamp(left + std::chrono::milliseconds(1), std::chrono::milliseconds(1), wait);
    }
    if (::poll(fds.data(), fds.size(), static_cast<int>(wait.count())) < 0 && errno != EINTR)
      return;
    if (fds[0].revents != 0) continue;  // woken to stop: the loop's condition ends it
    for (std::size_t k = 0; k < relays.size(); ++k) {
      Relay& r = *relays[k];
      const short client = fds[2 + 2 * k].revents, backend = fds[3 + 2 * k].revents;
      if ((client & (POLLIN | POLLHUP | POLLERR)) != 0 && !r.client_done) {
        const std::size_t before = r.to_backend.size();
        const Pulled pulled = pull(r.client.get(), r.to_backend);
        r.client_done = pulled != Pulled::kOpen;
        r.client_failed = pulled == Pulled::kFailed;
        if (r.to_backend.size() > before && !r.awaiting_since) r.awaiting_since = Clock::now();
      }
      if ((backend & (POLLIN | POLLHUP | POLLERR)) != 0 && !r.backend_done) {
        const std::size_t before = r.to_client.size();
        r.backend_done = pull(r.backend.get(), r.to_client) != Pulled::kOpen;
        if (r.to_client.size() > before) r.awaiting_since.reset();  // answered
      }
      if (!r.to_backend.empty() && !push(r.backend.get(), r.to_backend)) {
        r.backend_done = true;
        r.to_backend.clear();
      }
      if (!r.to_client.empty() && !push(r.client.get(), r.to_client)) r.client_failed = true;
      // The client closed its side: httplib learns it once what was in flight is through.
      if (r.client_done && r.to_backend.empty() && !r.backend_told) {
        ::shutdown(r.backend.get(), SHUT_WR);
        r.backend_told = true;
      }
    }
    reap(Clock::now());  // a finished answer's client sees the end of its stream at once
    if ((fds[1].revents & POLLIN) == 0) continue;
    while (true) {
      sockaddr_storage storage{};
      socklen_t length = sizeof storage;
      UniqueFd client(::accept4(listener_.get(), reinterpret_cast<sockaddr*>(&storage), &length,
                                SOCK_CLOEXEC | SOCK_NONBLOCK));
      if (!client.valid()) break;  // EAGAIN: none left (or a client that already left)
      const std::string peer = services::peer_of(storage);
      if (static_cast<int>(relays.size()) >= limits_.max_connections ||
          per_peer[peer] >= limits_.max_per_peer) {
        if (per_peer[peer] == 0) per_peer.erase(peer);
        continue;  // closed at once: its UniqueFd goes
      }
      UniqueFd backend = connect_backend(backend_port_);
      if (!backend.valid()) continue;
      ++per_peer[peer];
      relays.push_back(std::make_unique<Relay>(Relay{
          std::move(client), std::move(backend), peer, {}, {}, false, false, false, false, {}}));
    }
  }
}

}  // namespace pnp::dashboard
