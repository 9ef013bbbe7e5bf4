// Integration: pnp-dashboard over a real store, inference and simulation service, loaded
// in a real browser (Debian's headless Chromium): the DOM after the pages' scripts ran
// lists the runs, draws a run's curve from the live JSON with exactly its points, and
// draws played episodes; a screenshot of each page is saved beside the test's logs.
#include <gtest/gtest.h>
#include <httplib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"
#include "tests/integration/metrics_scrape.h"

namespace pnp::integration {
namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

store::MetricPoint point(long long steps, double success) {
  store::MetricPoint p;
  p.env_steps = steps;
  p.episodes = steps / 50;
  p.wall_s = static_cast<double>(steps) / 500;
  p.task_success = success;
  p.subtask_success = success;
  p.stop_score = success;
  return p;
}

class Dashboard : public ::testing::Test {
 protected:
  void SetUp() override {
    {
      store::RunStore store(db_);
      store::import_hierarchy(store, PNP_SOURCE_DIR "/tests/data/panda_block", "panda", "block");
      // A run still training, with three evaluations so far.
      training_run_ =
          store.create_run({"approach", "ddpg_her", "panda", "block", 7, "{}", "", std::nullopt})
              .id;
      store.set_state(training_run_, store::RunState::kRunning);
      for (const auto& [steps, success] : {std::pair{1000LL, 0.4}, {2000LL, 0.8}, {3000LL, 0.9}})
        store.record_metric(training_run_, point(steps, success), false, std::nullopt);
    }
    ASSERT_GT(sim_.port(), 0) << sim_.diagnostics();
    ASSERT_GT(inference_.port(), 0) << inference_.diagnostics();
    dashboard_.emplace(
        "dashboard",
        std::vector<std::string>{PNP_BIN_DIR "/pnp-dashboard", "--address", "127.0.0.1:0", "--db",
                                 db_, "--sim", loopback(sim_.port()), "--inference",
                                 loopback(inference_.port())},
        dir_.path());
    port_ = dashboard_->port();
    ASSERT_GT(port_, 0) << dashboard_->diagnostics();
  }

  std::string url(const std::string& path) const {
    return "http://127.0.0.1:" + std::to_string(port_) + path;
  }

  // The page's DOM once its scripts have run (virtual time: the polls happen at once),
  // and a screenshot of it saved as NAME.png in the test's directory.
  std::string browse(const std::string& path, const std::string& name) {
    const std::vector<std::string> common{PNP_CHROMIUM,        "--headless",
                                          "--no-sandbox",      "--disable-gpu",
                                          "--hide-scrollbars", "--virtual-time-budget=5000"};
    auto with = [&](std::vector<std::string> extra) {
      std::vector<std::string> args = common;
      args.insert(args.end(), extra.begin(), extra.end());
      return args;
    };
    ChildProcess dump(name + "_dom", with({"--dump-dom", url(path)}), dir_.path());
    const auto dumped = dump.wait(120s);
    EXPECT_TRUE(dumped && dumped->ok()) << dump.diagnostics();
    ChildProcess shot(name + "_png",
                      with({"--window-size=1280,1000",
                            "--screenshot=" + (dir_.path() / (name + ".png")).string(), url(path)}),
                      dir_.path());
    const auto shot_done = shot.wait(120s);
    EXPECT_TRUE(shot_done && shot_done->ok()) << shot.diagnostics();
    EXPECT_TRUE(std::filesystem::file_size(dir_.path() / (name + ".png")) > 10'000);
    return dump.stdout_text();
  }

  TempDir dir_{"dashboard"};
  const std::string db_ = dir_.file("pnp.db");
  ChildProcess sim_{
      "sim", {PNP_BIN_DIR "/pnp-sim-server", "--address", "127.0.0.1:0"}, dir_.path()};
  ChildProcess inference_{
      "inference",
      {PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db", db_, "--create-db"},
      dir_.path()};
  std::optional<ChildProcess> dashboard_;
  int port_ = 0;
  std::int64_t training_run_ = 0;
};

TEST_F(Dashboard, TheOverviewListsEveryRunAndWhatIsServed) {
  const std::string dom = browse("/", "overview");
  EXPECT_EQ(count(dom, "<tr class=\"run\""), 5) << dom;
  EXPECT_NE(dom.find("data-run=\"" + std::to_string(training_run_) + "\""), std::string::npos);
  EXPECT_NE(dom.find("<p id=\"serving\" data-ready=\"1\">"), std::string::npos) << dom;
  EXPECT_EQ(count(dom, "<tr><td>approach</td>"), 1) << "the promotions table";
}

TEST_F(Dashboard, ARunsCurveIsDrawnByItsScriptFromTheLiveJson) {
  // The server's page carries no curve: what the browser shows was drawn by the page's
  // polling script from /api/runs/ID, the same code that redraws as evaluations arrive.
  const std::string served = http_get(port_, "/runs/" + std::to_string(training_run_));
  EXPECT_NE(served.find("<div id=\"curve\" data-points=\"0\">"), std::string::npos) << served;
  const std::string dom = browse("/runs/" + std::to_string(training_run_), "run");
  EXPECT_NE(dom.find("<div id=\"curve\" data-points=\"3\">"), std::string::npos) << dom;
  EXPECT_NE(dom.find("class=\"series task_success\" data-points=\"3\""), std::string::npos);
  EXPECT_NE(dom.find("id=\"state\">running<"), std::string::npos);
  EXPECT_NE(dom.find("id=\"wall\">6.0 s<"), std::string::npos) << "the last evaluation's wall time";
  // A new evaluation is in the JSON the script polls.
  {
    store::RunStore store(db_);
    store.record_metric(training_run_, point(4000, 0.97), true, 4000);
  }
  const std::string json = http_get(port_, "/api/runs/" + std::to_string(training_run_));
  EXPECT_EQ(count(json, "\"env_steps\":"), 5) << json << " (the run's and four points)";
}

TEST_F(Dashboard, ARunsPageSaysWhereItsTimeWent) {
  const std::string path = "/runs/" + std::to_string(training_run_);
  EXPECT_NE(http_get(port_, path)
                .find("<p id=\"wall-breakdown\">Where its time went: nothing "
                      "recorded yet"),
            std::string::npos);
  {
    store::RunStore store(db_);
    store.add_wall_time(training_run_, {.rollout_s = 1.0,
                                        .update_s = 4.0,
                                        .eval_s = 4.5,
                                        .report_s = 0.25,
                                        .other_s = 0.25,
                                        .total_s = 10.0});
  }
  const std::string page = http_get(port_, path);
  EXPECT_NE(page.find("Where its time went (10.0 s in the parts that have ended): rollouts 1.0 s "
                      "(10.0%), updates 4.0 s (40.0%), evaluation 4.5 s (45.0%), checkpoints and "
                      "store writes 0.2 s (2.5%), other 0.2 s (2.5%).</p>"),
            std::string::npos)
      << page;
}

TEST_F(Dashboard, EpisodesOfTheServedHierarchyAreDrawn) {
  const std::string dom = browse("/episodes?count=2&seed=880000", "episodes");
  EXPECT_NE(dom.find("data-episodes=\"2\""), std::string::npos) << dom;
  EXPECT_EQ(count(dom, "class=\"episode\" data-steps=\"50\""), 2) << dom;
  EXPECT_GT(count(dom, "class=\"gripper subtask-approach\""), 0);
  EXPECT_NE(dom.find("(paper/panda/block, mocap hand, seed 880000)"), std::string::npos) << dom;
}

TEST_F(Dashboard, BadRequestsAreRefusedNamingTheParameter) {
  const std::string bad = http_get(port_, "/episodes?count=500");
  EXPECT_TRUE(bad.starts_with("HTTP/1.1 400")) << bad;
  EXPECT_NE(bad.find("count: expected an integer from 1 to 20, got &quot;500&quot;"),
            std::string::npos)
      << bad;
  EXPECT_TRUE(http_get(port_, "/runs/999999").starts_with("HTTP/1.1 404"));
  EXPECT_TRUE(http_get(port_, "/healthz").starts_with("HTTP/1.1 200"));
}

// With the platform's certificates and policy (scripts/make-dev-certs): HTTPS, and only a
// reader's token, sent as a bearer header, or given once at /login for a session, opens a
// page.
TEST(SecuredDashboard, OnlyAReaderGetsInOverHttps) {
  TempDir dir("dashboard_secured");
  const std::string certs = dir.file("certs");
  ASSERT_EQ(std::system((std::string(PNP_SOURCE_DIR) + "/scripts/make-dev-certs --out " + certs +
                         " 2>/dev/null")
                            .c_str()),
            0);
  { store::RunStore store(dir.file("pnp.db")); }
  ChildProcess dashboard("dashboard",
                         {PNP_BIN_DIR "/pnp-dashboard", "--address", "127.0.0.1:0", "--db",
                          dir.file("pnp.db"), "--tls-cert", certs + "/server.pem", "--tls-key",
                          certs + "/server.key", "--auth-policy", certs + "/policy.json"},
                         dir.path());
  const int port = dashboard.port();
  ASSERT_GT(port, 0) << dashboard.diagnostics();
  httplib::SSLClient https("127.0.0.1", port);
  https.set_ca_cert_path((certs + "/ca.pem").c_str());
  https.enable_server_certificate_verification(true);
  const auto status = [&](const std::string& path, const httplib::Headers& headers) {
    const auto answer = https.Get(path.c_str(), headers);
    return answer ? answer->status : -1;
  };
  const std::string reader = read_file(certs + "/reader.token");
  const std::string token = reader.substr(0, reader.find('\n'));
  EXPECT_EQ(status("/", {}), 401);
  EXPECT_EQ(status("/api/runs", {{"Authorization", "Bearer not-a-token"}}), 401);
  EXPECT_EQ(status("/", {{"Authorization", "Bearer " + token}}), 200);
  EXPECT_EQ(status("/api/runs", {{"Cookie", "pnp_token=" + token}}), 401)
      << "a token is never taken from a cookie";
  EXPECT_EQ(status("/healthz", {}), 200);
  // Signing in: the form's one-time nonce, sent back with the cookie /login set beside it.
  const auto form = [&] {
    const auto page = https.Get("/login");
    EXPECT_TRUE(page && page->status == 200);
    const std::string cookie = page->get_header_value("Set-Cookie");
    const std::string nonce = cookie.substr(10, cookie.find(';') - 10);  // "pnp_login=..."
    EXPECT_NE(page->body.find("value=\"" + nonce + "\""), std::string::npos) << page->body;
    return std::pair{nonce, httplib::Headers{{"Cookie", "pnp_login=" + nonce}}};
  };
  const auto post = [&](const std::string& target, const std::string& body,
                        const httplib::Headers& headers) {
    const auto answer =
        https.Post(target.c_str(), headers, body, "application/x-www-form-urlencoded");
    EXPECT_TRUE(answer);
    return answer ? *answer : httplib::Response{};
  };
  {  // A wrong token: refused, no session.
    const auto [nonce, headers] = form();
    const auto wrong = post("/login", "csrf=" + nonce + "&token=0123", headers);
    EXPECT_EQ(wrong.status, 401);
    EXPECT_EQ(wrong.get_header_value("Set-Cookie").find("pnp_session="), std::string::npos);
  }
  {  // The form's nonce is missing, forged, or not this browser's: another site's form.
    const auto [nonce, headers] = form();
    EXPECT_EQ(post("/login", "token=" + token, headers).status, 403);
    EXPECT_EQ(post("/login", "csrf=forged&token=" + token, {{"Cookie", "pnp_login=forged"}}).status,
              403);
    EXPECT_EQ(post("/login", "csrf=" + nonce + "&token=" + token, {}).status, 403);
  }
  {  // A token in the URL: refused (URLs are logged).
    const auto [nonce, headers] = form();
    EXPECT_EQ(post("/login?token=" + token, "csrf=" + nonce, headers).status, 400);
  }
  {  // An operator's token never goes into a browser.
    const std::string ops = read_file(certs + "/ops.token");
    const auto [nonce, headers] = form();
    const auto refused =
        post("/login", "csrf=" + nonce + "&token=" + ops.substr(0, ops.find('\n')), headers);
    EXPECT_EQ(refused.status, 401);
    EXPECT_NE(refused.body.find("may also act as operator"), std::string::npos) << refused.body;
  }
  const auto [nonce, headers] = form();
  const auto signed_in = post("/login", "csrf=" + nonce + "&token=" + token, headers);
  EXPECT_EQ(signed_in.status, 303);
  const std::string session = signed_in.get_header_value("Set-Cookie");
  EXPECT_TRUE(session.starts_with("pnp_session=")) << session;
  EXPECT_NE(session.find("; HttpOnly; Secure; SameSite=Strict; Path=/; Max-Age=28800"),
            std::string::npos)
      << session;
  EXPECT_EQ(session.find(token), std::string::npos) << "the cookie carries no token";
  const httplib::Headers browser{{"Cookie", session.substr(0, session.find(';'))}};
  EXPECT_EQ(status("/api/runs", browser), 200);
  // The nonce was used once; signing out ends the session on the server.
  EXPECT_EQ(post("/login", "csrf=" + nonce + "&token=" + token, headers).status, 403);
  EXPECT_EQ(post("/logout", "", browser).status, 303);
  EXPECT_EQ(status("/api/runs", browser), 401);
  // Plaintext to the HTTPS port gets nothing.
  EXPECT_TRUE(http_get(port, "/").find("200 OK") == std::string::npos);
  EXPECT_EQ(dashboard.stderr_text().find(token), std::string::npos) << "a token was logged";
}

// A client that never finishes its request holds nothing for long: before the front door
// (connection_guard.h), 8 connections sending a header line every 3 s held every httplib
// worker and /healthz timed out.
TEST(DashboardStart, SlowClientsNeverHoldUpAHealthCheck) {
  TempDir dir("dashboard_slow_clients");
  { store::RunStore store(dir.file("pnp.db")); }
  ChildProcess dashboard(
      "dashboard",
      {PNP_BIN_DIR "/pnp-dashboard", "--address", "127.0.0.1:0", "--db", dir.file("pnp.db"),
       "--max-connections-per-peer", "12", "--request-deadline-s", "3"},
      dir.path());
  const int port = dashboard.port();
  ASSERT_GT(port, 0) << dashboard.diagnostics();
  struct Slow {  // a connection, closed when it goes
    explicit Slow(int descriptor) : fd(descriptor) {}
    Slow(Slow&& other) noexcept : fd(std::exchange(other.fd, -1)) {}
    Slow& operator=(Slow&&) = delete;
    ~Slow() {
      if (fd >= 0) ::close(fd);
    }
    int fd;
  };
  std::vector<Slow> slow;
  const std::string head = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n";  // never ends
  for (int k = 0; k < 11; ++k) {
    slow.emplace_back(connect_loopback(port));
    ASSERT_GE(slow.back().fd, 0);
    ASSERT_EQ(::send(slow.back().fd, head.data(), head.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(head.size()));
  }
  // Each sends a header line every 300 ms, well within any read timeout, for as long as it
  // is let (httplib alone would keep a worker on each forever).
  std::jthread dribble([&slow](const std::stop_token& stop) {
    const std::string line = "X-Slow: 1\r\n";
    while (!stop.stop_requested()) {
      for (const Slow& c : slow)
        ::send(c.fd, line.data(), line.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
  });
  // Served beside them at once (the 12th connection of this address: within its share).
  EXPECT_TRUE(http_get(port, "/healthz").starts_with("HTTP/1.1 200")) << "held up";
  // Past its share, an address's next connection is closed unanswered.
  {
    std::vector<Slow> more;
    for (int k = 0; k < 2; ++k) more.emplace_back(connect_loopback(port));
    EXPECT_EQ(http_get(port, "/healthz"), "") << "a 14th connection of one address was served";
  }
  // Each slow request is closed at its deadline (3 s) however it dribbles: the end of the
  // stream (or a reset, for the lines it sent last), no answer.
  for (const Slow& s : slow) {
    timeval wait{10, 0};
    ::setsockopt(s.fd, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof wait);
    char byte = 0;
    const auto n = ::recv(s.fd, &byte, 1, 0);
    EXPECT_TRUE(n == 0 || (n < 0 && errno == ECONNRESET)) << "still open after its deadline";
  }
}

// httplib's default socket options would let a second dashboard bind the same port and
// take half the first one's requests; it is refused, as the gRPC servers refuse.
TEST(DashboardStart, RefusesAPortAlreadyInUse) {
  TempDir dir("dashboard_port_in_use");
  { store::RunStore store(dir.file("pnp.db")); }
  ChildProcess first(
      "first",
      {PNP_BIN_DIR "/pnp-dashboard", "--address", "127.0.0.1:0", "--db", dir.file("pnp.db")},
      dir.path());
  const int port = first.port();
  ASSERT_GT(port, 0) << first.diagnostics();
  ChildProcess second("second",
                      {PNP_BIN_DIR "/pnp-dashboard", "--address",
                       "127.0.0.1:" + std::to_string(port), "--db", dir.file("pnp.db")},
                      dir.path());
  const auto status = second.wait(30s);
  ASSERT_TRUE(status && status->exited && status->code == 1) << second.diagnostics();
  EXPECT_NE(second.stderr_text().find("cannot listen"), std::string::npos) << second.stderr_text();
  EXPECT_TRUE(http_get(port, "/healthz").starts_with("HTTP/1.1 200"));
}

TEST(DashboardStart, RefusesANonLoopbackAddressAndAMissingStore) {
  TempDir dir("dashboard_refusals");
  // Starts the dashboard on `db`; expects exit code 1 and returns what it said.
  const auto refusal = [&](const std::string& name, const std::string& db,
                           const std::vector<std::string>& more = {}) {
    std::vector<std::string> args{PNP_BIN_DIR "/pnp-dashboard", "--address", "0.0.0.0:0", "--db",
                                  db};
    args.insert(args.end(), more.begin(), more.end());
    ChildProcess dashboard(name, args, dir.path());
    const auto status = dashboard.wait(30s);
    EXPECT_TRUE(status && status->exited && status->code == 1) << dashboard.diagnostics();
    return dashboard.stderr_text();
  };
  EXPECT_NE(refusal("missing", dir.file("missing.db")).find("no store at"), std::string::npos);
  { store::RunStore store(dir.file("pnp.db")); }
  EXPECT_NE(refusal("exposed", dir.file("pnp.db")).find("plaintext HTTP is for loopback only"),
            std::string::npos);
  // TLS without a policy: anyone could read every run and play the served policy.
  EXPECT_NE(refusal("anonymous", dir.file("pnp.db"),
                    {"--tls-cert", dir.file("server.pem"), "--tls-key", dir.file("server.key")})
                .find("beyond loopback the dashboard needs --auth-policy"),
            std::string::npos);
}

}  // namespace
}  // namespace pnp::integration
