#pragma once
// The Prometheus scrape endpoint: a minimal HTTP/1.1 server on its own port and thread.
// GET /metrics answers the registry's text; other paths 404, other methods 405. One
// connection at a time (scrapes are rare), each closed after its answer; a client gets
// a bounded request size and a short deadline, so a slow or silent one cannot wedge it.

#include <chrono>
#include <string>
#include <thread>

#include "services/common/metrics_registry.h"
#include "services/common/unique_fd.h"

namespace pnp::services {

class MetricsHttpServer {
 public:
  // `address`: "host:port" ("127.0.0.1:0": any free loopback port; "[::1]:9100" for
  // IPv6). INVALID_ARGUMENT for a malformed address, UNAVAILABLE if it cannot listen.
  // `registry` must outlive the server.
  MetricsHttpServer(const std::string& address, const MetricsRegistry& registry);
  ~MetricsHttpServer();  // stops promptly: wakes the thread, joins it
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  int port() const { return port_; }

 private:
  void run(const std::stop_token& stop);
  void serve(int client) const;
  // Waits for `events` on fd until the deadline; false on timeout, error or stop.
  bool wait_for(int fd, short events, std::chrono::steady_clock::time_point deadline) const;

  const MetricsRegistry& registry_;
  UniqueFd listener_;
  UniqueFd wake_read_, wake_write_;  // self-pipe: the destructor's stop wakes poll()
  int port_ = 0;
  std::jthread thread_;  // last: joined before the descriptors close
};

}  // namespace pnp::services
