#pragma once
// The dashboard's front door. cpp-httplib (Debian 12's 0.11) gives each connection a
// worker thread from the moment it is accepted and has no deadline for a request: a few
// clients sending a header line every few seconds held every worker and /healthz timed
// out. The guard listens on the dashboard's public address and relays each connection,
// byte for byte (TLS passes through untouched), to httplib on a loopback port, so that:
//   - at most `max_connections` are open, and `max_per_peer` from one address (beyond:
//     closed at once), and httplib has a worker for every one of them;
//   - a request must be answered within `answer_deadline` of its first byte (a client
//     that never finishes its request head is closed then, its worker freed).

#include <chrono>
#include <string>
#include <thread>

#include "services/common/unique_fd.h"

namespace pnp::dashboard {

struct GuardLimits {
  int max_connections = 64;
  int max_per_peer = 16;  // a browser opens about six per site
  // From a request's first byte to the first byte of its answer: the slowest page plays
  // up to 20 episodes.
  std::chrono::milliseconds answer_deadline{30'000};
};

class ConnectionGuard {
 public:
  // Listens on `address` ("host:port", port 0: any) and relays to 127.0.0.1:`backend_port`.
  // UNAVAILABLE naming the address if it cannot listen.
  ConnectionGuard(const std::string& address, int backend_port, GuardLimits limits);
  ~ConnectionGuard();  // closes every connection, joins the thread
  ConnectionGuard(const ConnectionGuard&) = delete;
  ConnectionGuard& operator=(const ConnectionGuard&) = delete;

  int port() const { return port_; }

 private:
  struct Relay;
  void run(const std::stop_token& stop);

  int backend_port_;
  GuardLimits limits_;
  services::UniqueFd listener_;
  services::UniqueFd wake_read_, wake_write_;  // self-pipe: the destructor wakes poll()
  int port_ = 0;
  std::jthread thread_;  // last: joined before the descriptors close
};

}  // namespace pnp::dashboard
