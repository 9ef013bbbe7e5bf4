#pragma once
// Reading a server's Prometheus /metrics in integration tests: its port (from the server's
// "listening" log line), a plain HTTP GET over loopback, and sums of samples.

#include <string>
#include <vector>

#include "tests/integration/child_process.h"

namespace pnp::integration {

// A TCP connection to 127.0.0.1:port (-1 on failure); the caller closes it.
int connect_loopback(int port);

// GET http://127.0.0.1:port/path as HTTP/1.0 (so the body is never chunked), the whole
// response (headers included); empty on failure or after 30 s without a byte.
std::string http_get(int port, const std::string& path);

// The sum of a Prometheus family's samples whose labels include every one of `labels`.
double metric_sum(const std::string& exposition, const std::string& family,
                  const std::vector<std::string>& labels);

// The "metrics_port" of a server's "listening" log line (stderr's first); 0 if none.
int metrics_port(const ChildProcess& server);

}  // namespace pnp::integration
