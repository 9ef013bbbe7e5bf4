#include "clients/dashboard/dashboard_server.h"

#include <sys/socket.h>

#include <charconv>
#include <chrono>
#include <filesystem>
#include <thread>

#include "clients/dashboard/pages.h"
#include "common/error.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "services/common/address.h"
#include "services/common/transport_security.h"
#include "store/run_store.h"

namespace pnp::dashboard {
namespace {

constexpr std::uint64_t kHeldOutSeed = 424242;  // pnpctl evaluate's: no training run uses it
constexpr int kDefaultEpisodes = 5;
constexpr int kRunsListed = 200;
constexpr std::size_t kMaxRequestBodyBytes = 64 * 1024;

std::unique_ptr<store::Store> open_store(const DashboardConfig& config) {
  if (config.open_store) return config.open_store();
  if (config.db.empty()) throw_invalid_argument("--db", "the platform's store file", "none");
  if (!std::filesystem::exists(config.db))
    throw Error(ErrorCode::kFailedPrecondition, "--db: no store at " + config.db);
  return std::make_unique<store::RunStore>(
      config.db, store::DatabaseOptions{.access = store::Access::kReadOnly});
}

// HttpOnly: no script reads it; Secure: HTTPS only (a policy needs TLS); Strict: never
// sent from another site's page.
std::string cookie(const char* name, const std::string& value, const char* path,
                   std::chrono::seconds max_age) {
  return std::string(name) + "=" + value + "; HttpOnly; Secure; SameSite=Strict; Path=" + path +
         "; Max-Age=" + std::to_string(max_age.count());
}

int http_status(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return 400;
    case ErrorCode::kNotFound:
      return 404;
    case ErrorCode::kPermissionDenied:
      return 403;
    case ErrorCode::kFailedPrecondition:
      return 409;
    case ErrorCode::kUnavailable:
      return 503;
    default:
      return 500;
  }
}

// A query parameter as an integer in [lo, hi]; INVALID_ARGUMENT naming it otherwise.
long long integer_param(const httplib::Request& request, const std::string& name,
                        long long fallback, long long lo, long long hi) {
  if (!request.has_param(name)) return fallback;
  const std::string text = request.get_param_value(name);
  long long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value < lo || value > hi)
    throw_invalid_argument(name,
                           "an integer from " + std::to_string(lo) + " to " + std::to_string(hi),
                           "\"" + text + "\"");
  return value;
}

std::int64_t run_id_of(const httplib::Request& request) {
  std::int64_t id = 0;
  const std::string text = request.matches[1];
  std::from_chars(text.data(), text.data() + text.size(), id);
  return id;
}

store::RunFilter recent_runs() {
  store::RunFilter filter;
  filter.limit = kRunsListed;
  return filter;
}

ServingView serving_view(const std::shared_ptr<grpc::Channel>& inference) {
  ServingView view;
  auto stub = policy::v1::PolicyService::NewStub(inference);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  policy::v1::GetServingStatusResponse status;
  const grpc::Status rpc = stub->GetServingStatus(&context, {}, &status);
  if (!rpc.ok()) {
    view.error = rpc.error_message();
    return view;
  }
  view.ready = status.ready();
  return view;
}

// Runs `body`, turning a pnp::Error (or anything else) into a page with its status.
template <typename Body>
void answer(httplib::Response& response, Body&& body) {
  try {
    body();
  } catch (const Error& e) {
    response.status = http_status(e.code());
    response.set_content(error_page(response.status, e.what()), "text/html; charset=utf-8");
  } catch (const std::exception& e) {
    response.status = 500;
    response.set_content(error_page(500, e.what()), "text/html; charset=utf-8");
  }
}

std::unique_ptr<httplib::Server> make_http(const DashboardConfig& config) {
  if (config.tls_cert.empty() != config.tls_key.empty())
    throw_invalid_argument("--tls-cert and --tls-key", "both (HTTPS) or neither", "one of them");
  if (config.tls_cert.empty()) return std::make_unique<httplib::Server>();
  auto server =
      std::make_unique<httplib::SSLServer>(config.tls_cert.c_str(), config.tls_key.c_str());
  if (!server->is_valid())
    throw_invalid_argument("--tls-cert and --tls-key", "a readable PEM certificate and its key",
                           config.tls_cert + ", " + config.tls_key);
  return server;
}

// What would let strangers read the platform, or send a token in the clear, is refused.
void check_exposure(const DashboardConfig& config) {
  services::validate_address(config.address, "--address");
  const bool tls = !config.tls_cert.empty();
  if (config.policy && !tls)
    throw Error(ErrorCode::kFailedPrecondition,
                "--auth-policy needs --tls-cert and --tls-key: tokens are never taken over "
                "plaintext");
  if (!tls && !services::is_loopback_address(config.address))
    throw Error(ErrorCode::kFailedPrecondition,
                "--address " + config.address +
                    ": plaintext HTTP is for loopback only; give --tls-cert and --tls-key (and "
                    "--auth-policy: readers only), or reach it through an SSH tunnel");
  // It shows every run and plays the served policy: strangers sign in first.
  if (!config.policy && !services::is_loopback_address(config.address))
    throw Error(ErrorCode::kFailedPrecondition,
                "--address " + config.address +
                    ": beyond loopback the dashboard needs --auth-policy (readers sign in "
                    "with a token), or reach it through an SSH tunnel");
}

}  // namespace

DashboardServer::DashboardServer(DashboardConfig config)
    : config_(std::move(config)),
      access_(config_.policy),
      store_(open_store(config_)),
      player_(config_.sim, config_.inference) {
  check_exposure(config_);
  http_ = make_http(config_);
  // httplib's default also sets SO_REUSEPORT, so a second dashboard on a port in use would
  // bind beside the first and take half its requests: only SO_REUSEADDR (a restart may
  // rebind at once), and a port in use is refused as the gRPC servers refuse it.
  http_->set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  // Requests are small (a login form at most): a large body is refused before it is read.
  http_->set_payload_max_length(kMaxRequestBodyBytes);
  // A worker for every connection the guard lets through (httplib's default is 8).
  http_->new_task_queue = [workers = static_cast<std::size_t>(config_.guard.max_connections) + 2] {
    return std::make_unique<httplib::ThreadPool>(workers).release();  // httplib owns it
  };
  routes();
  // httplib listens on loopback only; the guard serves the public address and relays.
  const int backend = http_->bind_to_any_port("127.0.0.1");
  if (backend <= 0)
    throw Error(ErrorCode::kUnavailable, "dashboard: cannot listen on a loopback port");
  thread_ = std::jthread([this] { http_->listen_after_bind(); });
  // httplib's stop() does nothing until the listening loop has started: wait for it, so
  // that a destructor right after the constructor cannot hang the join.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!http_->is_running() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  try {
    guard_ = std::make_unique<ConnectionGuard>(config_.address, backend, config_.guard);
  } catch (...) {
    http_->stop();
    throw;
  }
  port_ = guard_->port();
}

DashboardServer::~DashboardServer() {
  guard_.reset();  // its connections end, and with them httplib's workers' reads
  http_->stop();
}

void DashboardServer::routes() {
  if (access_.enforced()) login_routes();
  http_->Get("/healthz", [](const httplib::Request&, httplib::Response& response) {
    response.set_content("ok\n", "text/plain");
  });
  http_->Get("/", [this](const httplib::Request&, httplib::Response& response) {
    answer(response, [&] {
      std::vector<store::RunRecord> runs;
      std::vector<store::Promotion> promotions;
      {
        std::lock_guard lock(store_mutex_);
        runs = store_->list_runs(recent_runs());
        promotions = store_->promotions();
      }
      ServingView serving = serving_view(config_.inference);
      if (serving.ready) {
        try {
          const ServedWorld w = player_.served_world();
          serving.world = w.world + "/" + w.robot + "/" + w.object + " (" + w.actuation + " hand)";
        } catch (const Error&) {  // the page still shows what the store says
        }
      }
      response.set_content(overview_page(runs, promotions, serving), "text/html; charset=utf-8");
    });
  });
  http_->Get(R"(/runs/(\d+))", [this](const httplib::Request& request,
                                      httplib::Response& response) {
    answer(response, [&] {
      std::lock_guard lock(store_mutex_);
      const auto run = store_->get_run(run_id_of(request));
      response.set_content(run_page(run, store_->checkpoints(run.id)), "text/html; charset=utf-8");
    });
  });
  http_->Get("/api/runs", [this](const httplib::Request&, httplib::Response& response) {
    answer(response, [&] {
      nlohmann::json out = nlohmann::json::array();
      std::lock_guard lock(store_mutex_);
      for (const auto& run : store_->list_runs(recent_runs())) out.push_back(run_json(run, {}));
      response.set_content(out.dump(), "application/json");
    });
  });
  http_->Get(
      R"(/api/runs/(\d+))", [this](const httplib::Request& request, httplib::Response& response) {
        answer(response, [&] {
          std::lock_guard lock(store_mutex_);
          const auto run = store_->get_run(run_id_of(request));
          response.set_content(run_json(run, store_->metrics(run.id)).dump(), "application/json");
        });
      });
  http_->Get("/episodes", [this](const httplib::Request& request, httplib::Response& response) {
    answer(response, [&] {
      const auto count =
          integer_param(request, "count", kDefaultEpisodes, 1, EpisodePlayer::kMaxEpisodes);
      const auto seed = integer_param(request, "seed", kHeldOutSeed, 0, 1LL << 62);
      const PlayedEpisodes played =
          player_.play(static_cast<int>(count), static_cast<std::uint64_t>(seed));
      response.set_content(episodes_page(played), "text/html; charset=utf-8");
    });
  });
}

void DashboardServer::login_routes() {
  // Every request but /login, /logout and /healthz needs a reader.
  http_->set_pre_routing_handler(
      [this](const httplib::Request& request, httplib::Response& response) {
        if (request.path == "/login" || request.path == "/logout" || request.path == "/healthz")
          return httplib::Server::HandlerResponse::Unhandled;
        const auto decision = access_.decide(request);
        if (decision.outcome == security::AccessDecision::Outcome::kAllowed)
          return httplib::Server::HandlerResponse::Unhandled;
        const bool unauthenticated =
            decision.outcome == security::AccessDecision::Outcome::kUnauthenticated;
        response.status = unauthenticated ? 401 : 403;
        response.set_content(access_page(response.status, decision.message),
                             "text/html; charset=utf-8");
        return httplib::Server::HandlerResponse::Handled;
      });
  http_->Get("/login", [this](const httplib::Request&, httplib::Response& response) {
    show_login(response, 200, "");
  });
  http_->Post("/login", [this](const httplib::Request& request, httplib::Response& response) {
    // A URL is logged by proxies and kept in histories: the token comes in the body only.
    if (request.target.find('?') != std::string::npos) {
      show_login(response, 400, "the token goes in the form's body, never in the URL");
      return;
    }
    const std::string nonce = request.get_param_value("csrf");
    if (nonce.empty() || nonce != cookie_value(request.get_header_value("Cookie"), kLoginCookie) ||
        !access_.sessions().redeem_login_nonce(nonce)) {
      show_login(response, 403,
                 "this sign-in form expired or came from another site: sign in "
                 "from this page");
      return;
    }
    const SignIn signed_in = access_.sign_in(request.get_param_value("token"));
    if (!signed_in.session_id) {
      show_login(response, 401, signed_in.refusal);
      return;
    }
    response.set_header("Set-Cookie", cookie(kSessionCookie, *signed_in.session_id, "/",
                                             access_.sessions().lifetime()));
    response.set_redirect("/", 303);
  });
  http_->Post("/logout", [this](const httplib::Request& request, httplib::Response& response) {
    access_.sessions().close(cookie_value(request.get_header_value("Cookie"), kSessionCookie));
    response.set_header("Set-Cookie", cookie(kSessionCookie, "", "/", std::chrono::seconds(0)));
    response.set_redirect("/login", 303);
  });
}

void DashboardServer::show_login(httplib::Response& response, int status,
                                 const std::string& error) {
  // A fresh one-time nonce, in the form and in a cookie only this site's pages send back.
  const std::string nonce = access_.sessions().issue_login_nonce();
  response.status = status;
  response.set_header("Set-Cookie",
                      cookie(kLoginCookie, nonce, "/login", SessionBook::kLoginFormLifetime));
  response.set_content(login_page(error, nonce), "text/html; charset=utf-8");
}

}  // namespace pnp::dashboard
