#pragma once
// The Prometheus scrape endpoint: a minimal HTTP/1.1 server on its own port and thread.
// GET /metrics answers the registry's text; other paths 404, other methods 405. Every
// connection is served side by side by one poll() loop, each closed after its answer; a
// client gets a bounded request size and a deadline for its whole request head, and at
// most kMaxConnections are open (kMaxConnectionsPerPeer per address), so slow or silent
// clients cannot hold a scrape up nor take every slot.

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "services/common/metrics_registry.h"
#include "services/common/unique_fd.h"

namespace pnp::services {

struct MetricsHttpLimits {
  std::chrono::milliseconds header_deadline{2000};  // from accept to the request head's end
  std::chrono::milliseconds write_deadline{5000};
  std::chrono::milliseconds linger{500};  // reading what the client still sends, after
  int max_connections = 64;
  int max_connections_per_peer = 8;  // beyond: closed at once
};

class MetricsHttpServer {
 public:
  // `address`: "host:port" ("127.0.0.1:0": any free loopback port; "[::1]:9100" for
  // IPv6). INVALID_ARGUMENT for a malformed address, UNAVAILABLE if it cannot listen.
  // `registry` must outlive the server.
  MetricsHttpServer(const std::string& address, const MetricsRegistry& registry,
                    MetricsHttpLimits limits = {});
  ~MetricsHttpServer();  // stops promptly: wakes the thread, joins it
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  int port() const { return port_; }

 private:
  struct Connection;
  void run(const std::stop_token& stop);
  void accept_all(std::vector<Connection>& open) const;
  // Moves the connection on by what its socket allows now; false once it is done.
  bool advance(Connection& c) const;
  std::string answer(const std::string& request) const;

  const MetricsRegistry& registry_;
  MetricsHttpLimits limits_;
  UniqueFd listener_;
  UniqueFd wake_read_, wake_write_;  // self-pipe: the destructor's stop wakes poll()
  int port_ = 0;
  std::jthread thread_;  // last: joined before the descriptors close
};

}  // namespace pnp::services
