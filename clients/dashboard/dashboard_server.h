#pragma once
// pnp-dashboard's HTTP side (cpp-httplib): the store read-only and the inference and
// simulation services as a client. Routes:
//   /                 runs, what is served and the promotions
//   /runs/ID          a run, its checkpoints, and its learning curve drawn live
//   /episodes         ?count=N&seed=S: held-out episodes of the served hierarchy, drawn
//   /api/runs, /api/runs/ID   the same as JSON
//   /healthz
//   /login, /logout   (with an authorization policy) a reader's token for a session
// Every handler answers with a status and a message naming the problem; none throws.
// httplib listens on a loopback port; the public address is the ConnectionGuard's.

#include <httplib.h>

#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "clients/dashboard/connection_guard.h"
#include "clients/dashboard/dashboard_access.h"
#include "clients/dashboard/episode_player.h"
#include "store/store.h"

namespace pnp::dashboard {

struct DashboardConfig {
  std::string address = "127.0.0.1:8080";  // beyond loopback only with TLS
  std::string db;                          // the store file, read only ...
  store::StoreOpener open_store{};         // ... unless set: the store through pnp-store-server
  std::shared_ptr<grpc::Channel> sim, inference;
  std::string tls_cert, tls_key;                       // both: HTTPS
  std::shared_ptr<const security::AuthPolicy> policy;  // set: readers only (needs TLS)
  GuardLimits guard{};  // connections per address, and the deadline to answer a request
};

class DashboardServer {
 public:
  // Opens the store (a file read-only, which must exist; or through the store server) and
  // listens; INVALID_ARGUMENT or
  // FAILED_PRECONDITION naming the flag (plaintext beyond loopback, a policy without
  // TLS, unreadable certificates), UNAVAILABLE if it cannot listen.
  explicit DashboardServer(DashboardConfig config);
  ~DashboardServer();  // stops listening and joins the server thread
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  int port() const { return port_; }

 private:
  void routes();
  void login_routes();
  // The sign-in page with `error` (empty: none) and a fresh one-time form nonce.
  void show_login(httplib::Response& response, int status, const std::string& error);

  DashboardConfig config_;
  DashboardAccess access_;
  std::mutex store_mutex_;  // one handle, used by one handler at a time
  std::unique_ptr<store::Store> store_;
  EpisodePlayer player_;
  std::unique_ptr<httplib::Server> http_;  // an httplib::SSLServer with TLS
  int port_ = 0;
  std::jthread thread_;                     // httplib's, on a loopback port only the guard reaches
  std::unique_ptr<ConnectionGuard> guard_;  // the public address; closed first
};

}  // namespace pnp::dashboard
