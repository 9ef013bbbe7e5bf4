#pragma once
// pnp-dashboard's HTTP side (cpp-httplib): the store read-only and the inference and
// simulation services as a client. Routes:
//   /                 runs, what is served and the promotions
//   /runs/ID          a run, its checkpoints, and its learning curve drawn live
//   /episodes         ?count=N&seed=S: held-out episodes of the served hierarchy, drawn
//   /api/runs, /api/runs/ID   the same as JSON
//   /healthz
// Every handler answers with a status and a message naming the problem; none throws.

#include <httplib.h>

#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "clients/dashboard/episode_player.h"
#include "store/run_store.h"

namespace pnp::dashboard {

struct DashboardConfig {
  std::string address = "127.0.0.1:8080";  // loopback only (plaintext, no authentication)
  std::string db;
  std::shared_ptr<grpc::Channel> sim, inference;
};

class DashboardServer {
 public:
  // Opens the store read-only (it must exist) and listens; INVALID_ARGUMENT or
  // FAILED_PRECONDITION naming the flag, UNAVAILABLE if it cannot listen.
  explicit DashboardServer(DashboardConfig config);
  ~DashboardServer();  // stops listening and joins the server thread
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  int port() const { return port_; }

 private:
  void routes();

  DashboardConfig config_;
  std::mutex store_mutex_;  // one connection, used by one handler at a time
  store::RunStore store_;
  EpisodePlayer player_;
  httplib::Server http_;
  int port_ = 0;
  std::jthread thread_;  // last: joined before the rest goes
};

}  // namespace pnp::dashboard
