#pragma once
// A rosmaster of one's own on a free loopback port, for the tests and benchmarks that run
// ROS 1 nodes (the stand-in Franka and the bridge): started with `--core -p 0`, its URI
// read from the log it writes. Nodes given node_env() use it, advertise loopback
// addresses only and log under the owner's directory. No ROS headers: C++17 and C++20
// callers alike.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "tests/integration/child_process.h"

namespace pnp::integration {

class RosMaster {
 public:
  // Logs under `dir`; throws std::runtime_error if rosmaster names no URI within 30 s.
  explicit RosMaster(const std::filesystem::path& dir);

  const std::string& uri() const { return uri_; }
  // ROS_MASTER_URI and the rest, for a node's environment (or setenv, for this process).
  std::vector<std::pair<std::string, std::string>> node_env() const;
  std::string diagnostics() const { return process_.diagnostics(); }

 private:
  std::filesystem::path dir_;
  ChildProcess process_;
  std::string uri_;
};

}  // namespace pnp::integration
