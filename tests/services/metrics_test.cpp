// Prometheus metrics: the registry over prometheus-cpp (its text, its refusals, thread
// safety), the HTTP endpoint over a loopback socket, and the RPC interceptor's standard
// gRPC series on an in-process server.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "common/error.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "services/common/metrics_http_server.h"
#include "services/common/metrics_registry.h"
#include "services/common/server_runtime.h"
#include "services/common/unique_fd.h"
#include "services/sim/sim_service.h"

namespace pnp::services {
namespace {

namespace sv1 = pnp::sim::v1;

template <typename Body>
ErrorCode code_of(Body&& body) {
  try {
    body();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "no pnp::Error thrown";
  return ErrorCode::kInternal;
}

// Sends `request` to 127.0.0.1:port and returns everything the server answers.
std::string http(int port, const std::string& request) {
  const UniqueFd fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
    return "connect failed";
  for (std::size_t sent = 0; sent < request.size();) {
    const auto n = ::send(fd.get(), request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
  std::string answer;
  std::array<char, 4096> buffer{};
  for (;;) {
    const auto n = ::recv(fd.get(), buffer.data(), buffer.size(), 0);
    if (n <= 0) break;
    answer.append(buffer.data(), static_cast<std::size_t>(n));
  }
  return answer;
}

bool has_line(const std::string& text, const std::string& line) {
  return ("\n" + text).find("\n" + line + "\n") != std::string::npos;
}

TEST(MetricsRegistry, RendersEveryFamilyInTheTextFormat) {
  MetricsRegistry r;
  auto& h = r.histogram("c_seconds", "C.", {0.5, 1}, {{"code", "OK"}});
  for (double v : {0.25, 0.5, 0.75, 4.0}) h.Observe(v);
  r.counter("b_total", "B things.", {{"path", "a\\b\"c\nd"}, {"a", "x"}}).Increment(2);
  r.counter("b_total", "B things.", {{"a", "w"}, {"path", "p"}}).Increment();
  r.gauge("a_gauge", "A gauge.").Set(-1.5);
  const std::string text = r.render();
  for (const char* line :
       {"# HELP a_gauge A gauge.", "# TYPE a_gauge gauge", "a_gauge -1.5",
        "# HELP b_total B things.", "# TYPE b_total counter", "b_total{a=\"w\",path=\"p\"} 1",
        "b_total{a=\"x\",path=\"a\\\\b\\\"c\\nd\"} 2", "# TYPE c_seconds histogram",
        "c_seconds_count{code=\"OK\"} 4", "c_seconds_sum{code=\"OK\"} 5.5",
        "c_seconds_bucket{code=\"OK\",le=\"0.5\"} 2", "c_seconds_bucket{code=\"OK\",le=\"1\"} 3",
        "c_seconds_bucket{code=\"OK\",le=\"+Inf\"} 4"})
    EXPECT_TRUE(has_line(text, line)) << line << "\n" << text;
}

TEST(MetricsRegistry, TheSameNameAndLabelsGiveTheSameMetric) {
  MetricsRegistry r;
  Counter& a = r.counter("x_total", "X.", {{"a", "1"}, {"b", "2"}});
  EXPECT_EQ(&a, &r.counter("x_total", "X.", {{"b", "2"}, {"a", "1"}}));
  EXPECT_NE(&a, &r.counter("x_total", "X.", {{"a", "1"}, {"b", "3"}}));
  Histogram& h = r.histogram("y_seconds", "Y.", {1e-4, 1});
  EXPECT_EQ(&h, &r.histogram("y_seconds", "Y.", {1e-4, 1}));
}

TEST(MetricsRegistry, RefusesInvalidNamesAndInconsistentFamilies) {
  MetricsRegistry r;
  const auto invalid = [](auto&& body) { return code_of(body) == ErrorCode::kInvalidArgument; };
  EXPECT_TRUE(invalid([&] { r.counter("", "h"); }));
  EXPECT_TRUE(invalid([&] { r.counter("1st_total", "h"); }));
  EXPECT_TRUE(invalid([&] { r.counter("bad-name", "h"); }));
  EXPECT_TRUE(invalid([&] { r.counter("ok_total", "h", {{"bad-label", "v"}}); }));
  EXPECT_TRUE(invalid([&] { r.counter("ok_total", "h", {{"a:b", "v"}}); }));
  EXPECT_TRUE(invalid([&] { r.counter("ok_total", "h", {{"__reserved", "v"}}); }));
  EXPECT_TRUE(invalid([&] { r.counter("ok_total", "h", {{"a", "1"}, {"a", "2"}}); }));
  EXPECT_TRUE(invalid([&] { r.histogram("h_seconds", "h", {1}, {{"le", "1"}}); }));
  EXPECT_TRUE(invalid([&] { r.histogram("h_seconds", "h", {1, 1}); }));
  EXPECT_TRUE(invalid([&] { r.histogram("h_seconds", "h", {1, 0.5}); }));

  r.counter("colon:name_total", "h", {{"a", "1"}});  // colons are valid in metric names
  EXPECT_TRUE(invalid([&] { r.gauge("colon:name_total", "h", {{"a", "1"}}); }));  // two types
  EXPECT_TRUE(invalid([&] { r.counter("colon:name_total", "other help", {{"a", "1"}}); }));
  EXPECT_TRUE(invalid([&] { r.counter("colon:name_total", "h", {{"b", "1"}}); }));

  r.histogram("lat_seconds", "h", {1});
  EXPECT_TRUE(invalid([&] { r.histogram("lat_seconds", "h", {2}); }));
  EXPECT_TRUE(invalid([&] { r.gauge("lat_seconds_count", "h"); }));
  r.counter("q_sum", "h");
  EXPECT_TRUE(invalid([&] { r.histogram("q", "h", {1}); }));
}

TEST(MetricsRegistry, ConcurrentUpdatesSumExactly) {
  MetricsRegistry r;
  constexpr int kThreads = 4;
  constexpr int kEach = 20'000;
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&r, t] {
        // Each thread looks the metrics up itself: lookups race with updates.
        Counter& c = r.counter("hits_total", "h", {{"shared", "yes"}});
        Histogram& h = r.histogram("obs", "h", {0.5});
        Gauge& g = r.gauge("level", "h");
        for (int k = 0; k < kEach; ++k) {
          c.Increment();
          h.Observe(k % 2 == 0 ? 0.25 : 1.0);
          g.Increment();
          g.Decrement();
          if (k % 1000 == 0) static_cast<void>(r.render());
        }
        r.counter("per_thread_total", "h", {{"t", std::to_string(t)}}).Increment(kEach);
      });
    }
  }
  const std::string text = r.render();
  EXPECT_TRUE(has_line(text, "hits_total{shared=\"yes\"} 80000")) << text;
  EXPECT_TRUE(has_line(text, "obs_bucket{le=\"0.5\"} 40000")) << text;
  EXPECT_TRUE(has_line(text, "obs_count 80000")) << text;
  EXPECT_TRUE(has_line(text, "obs_sum 50000")) << text;
  EXPECT_TRUE(has_line(text, "level 0")) << text;
  for (int t = 0; t < kThreads; ++t)
    EXPECT_TRUE(has_line(text, "per_thread_total{t=\"" + std::to_string(t) + "\"} 20000"));
}

TEST(MetricsHttpServer, ServesMetricsAndRefusesOtherRequests) {
  MetricsRegistry r;
  r.counter("x_total", "X.").Increment(3);
  MetricsHttpServer server("127.0.0.1:0", r);
  ASSERT_GT(server.port(), 0);

  const std::string ok = http(server.port(), "GET /metrics HTTP/1.1\r\nHost: a\r\n\r\n");
  EXPECT_TRUE(ok.starts_with("HTTP/1.1 200 OK\r\n")) << ok;
  EXPECT_NE(ok.find("\r\nContent-Type: text/plain; version=0.0.4; charset=utf-8\r\n"),
            std::string::npos);
  EXPECT_NE(ok.find("\r\nConnection: close\r\n"), std::string::npos);
  const std::string body = r.render();
  EXPECT_TRUE(ok.ends_with("\r\n\r\n" + body)) << ok;
  EXPECT_NE(ok.find("\r\nContent-Length: " + std::to_string(body.size()) + "\r\n"),
            std::string::npos);
  EXPECT_TRUE(has_line(ok, "x_total 3"));

  EXPECT_TRUE(http(server.port(), "GET /metrics?x=1 HTTP/1.0\r\n\r\n").starts_with("HTTP/1.1 200"));
  EXPECT_TRUE(http(server.port(), "GET / HTTP/1.1\r\n\r\n").starts_with("HTTP/1.1 404 "));
  EXPECT_TRUE(http(server.port(), "GET /metricsx HTTP/1.1\r\n\r\n").starts_with("HTTP/1.1 404 "));
  const std::string post = http(server.port(), "POST /metrics HTTP/1.1\r\n\r\n");
  EXPECT_TRUE(post.starts_with("HTTP/1.1 405 ")) << post;
  EXPECT_NE(post.find("\r\nAllow: GET\r\n"), std::string::npos);
  EXPECT_TRUE(http(server.port(), "nonsense\r\n\r\n").starts_with("HTTP/1.1 400 "));
  EXPECT_TRUE(http(server.port(), "GET /" + std::string(10'000, 'a')).starts_with("HTTP/1.1 431 "));
  // After all that, it still answers.
  EXPECT_TRUE(http(server.port(), "GET /metrics HTTP/1.1\r\n\r\n").starts_with("HTTP/1.1 200"));
}

TEST(MetricsHttpServer, StopsWithASilentClientConnected) {
  MetricsRegistry r;
  auto server = std::make_unique<MetricsHttpServer>("127.0.0.1:0", r);
  const UniqueFd silent(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(server->port()));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(silent.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address),
            0);
  server.reset();  // must return although the client never sends a byte
}

// A loopback connection that sends `head` (an unfinished request) and then waits.
UniqueFd slow_client(int port, const std::string& head) {
  UniqueFd fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(::connect(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  if (!head.empty()) {
    EXPECT_EQ(::send(fd.get(), head.data(), head.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(head.size()));
  }
  return fd;
}

// Still open and unanswered: nothing to read yet, no end of stream.
bool waiting(const UniqueFd& fd) {
  std::array<char, 16> buffer{};
  const auto n = ::recv(fd.get(), buffer.data(), buffer.size(), MSG_DONTWAIT);
  return n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);
}

// Slow and silent clients are served beside a scrape, not before it: twelve connections
// that never finish their request head (a deadline longer than the test) are all still
// open and unanswered when the scrape has been answered.
TEST(MetricsHttpServer, SlowClientsNeverHoldUpAScrape) {
  MetricsRegistry r;
  r.counter("x_total", "X.").Increment();
  MetricsHttpLimits limits;
  limits.header_deadline = std::chrono::minutes(10);
  limits.max_connections_per_peer = 16;
  MetricsHttpServer server("127.0.0.1:0", r, limits);
  std::vector<UniqueFd> slow;
  for (int k = 0; k < 12; ++k)
    slow.push_back(slow_client(server.port(), k % 2 == 0 ? "" : "GET /metrics HTTP/1.1\r\n"));
  const std::string ok = http(server.port(), "GET /metrics HTTP/1.1\r\n\r\n");
  EXPECT_TRUE(ok.starts_with("HTTP/1.1 200 OK\r\n")) << ok;
  for (const auto& fd : slow) EXPECT_TRUE(waiting(fd));
}

// One address cannot take every slot: past its share, its next connection is closed at
// once (unanswered), and another of its connections is served once a slot of its frees.
TEST(MetricsHttpServer, OnePeerHoldsAtMostItsShareOfConnections) {
  MetricsRegistry r;
  MetricsHttpLimits limits;
  limits.header_deadline = std::chrono::minutes(10);
  limits.max_connections_per_peer = 4;
  MetricsHttpServer server("127.0.0.1:0", r, limits);
  std::vector<UniqueFd> held;
  for (int k = 0; k < 4; ++k) held.push_back(slow_client(server.port(), ""));
  EXPECT_EQ(http(server.port(), "GET /metrics HTTP/1.1\r\n\r\n"), "") << "a fifth was served";
  for (const auto& fd : held) EXPECT_TRUE(waiting(fd));
  held.pop_back();  // closes one: its slot frees once the server sees it
  std::string ok;
  for (int attempt = 0; attempt < 100 && !ok.starts_with("HTTP/1.1 200"); ++attempt) {
    ok = http(server.port(), "GET /metrics HTTP/1.1\r\n\r\n");
    if (!ok.starts_with("HTTP/1.1 200")) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(ok.starts_with("HTTP/1.1 200 OK\r\n")) << ok;
}

TEST(MetricsHttpServer, RefusesBadAddressesNamingThem) {
  MetricsRegistry r;
  MetricsHttpServer first("127.0.0.1:0", r);
  const std::string taken = "127.0.0.1:" + std::to_string(first.port());
  try {
    MetricsHttpServer second(taken, r);
    FAIL() << "two servers on " << taken;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnavailable);
    EXPECT_NE(std::string(e.what()).find(taken), std::string::npos) << e.what();
  }
  for (const char* bad : {"no-port", "127.0.0.1:", "127.0.0.1:70000", "127.0.0.1:http"})
    EXPECT_EQ(code_of([&] { MetricsHttpServer s(bad, r); }), ErrorCode::kInvalidArgument) << bad;
}

class RpcMetricsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    runtime_ = std::make_unique<ServerRuntime>(
        ServerConfig{.address = "127.0.0.1:0",
                     .max_message_bytes = 4 << 20,
                     .services = {&service_},
                     .service_names = {"pnp.sim.v1.SimulationService"},
                     .metrics = &metrics_,
                     .metrics_address = "127.0.0.1:0"});
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(runtime_->port()),
                                   grpc::InsecureChannelCredentials());
    stub_ = sv1::SimulationService::NewStub(channel_);
  }
  void TearDown() override { runtime_->shutdown(std::chrono::milliseconds(500)); }

  grpc::StatusCode get_env_spec(common::v1::Robot robot) {
    grpc::ClientContext c;
    sv1::GetEnvSpecRequest r;
    sv1::GetEnvSpecResponse out;
    r.set_robot(robot);
    r.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    return stub_->GetEnvSpec(&c, r, &out).error_code();
  }

  MetricsRegistry metrics_;
  SimServiceImpl service_{&metrics_};
  std::unique_ptr<ServerRuntime> runtime_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<sv1::SimulationService::Stub> stub_;
};

// go-grpc-prometheus' label order: prometheus-cpp writes labels sorted by name.
std::string grpc_labels(const std::string& code, const std::string& method,
                        const std::string& type = "unary") {
  return "{" + (code.empty() ? "" : "grpc_code=\"" + code + "\",") + "grpc_method=\"" + method +
         "\",grpc_service=\"pnp.sim.v1.SimulationService\",grpc_type=\"" + type + "\"}";
}

TEST_F(RpcMetricsTest, CountsEachCallWithTheStandardGrpcNames) {
  ASSERT_EQ(get_env_spec(common::v1::ROBOT_FETCH), grpc::StatusCode::OK);
  ASSERT_EQ(get_env_spec(common::v1::ROBOT_PANDA), grpc::StatusCode::OK);
  ASSERT_EQ(get_env_spec(common::v1::ROBOT_UNSPECIFIED), grpc::StatusCode::INVALID_ARGUMENT);

  const std::string text = metrics_.render();
  EXPECT_TRUE(has_line(text, "grpc_server_started_total" + grpc_labels("", "GetEnvSpec") + " 3"))
      << text;
  EXPECT_TRUE(has_line(text, "grpc_server_handled_total" + grpc_labels("OK", "GetEnvSpec") + " 2"));
  EXPECT_TRUE(has_line(
      text, "grpc_server_handled_total" + grpc_labels("InvalidArgument", "GetEnvSpec") + " 1"));
  EXPECT_TRUE(
      has_line(text, "grpc_server_handling_seconds_count" + grpc_labels("", "GetEnvSpec") + " 3"));
  EXPECT_NE(text.find("# TYPE grpc_server_handling_seconds histogram\n"), std::string::npos);
  EXPECT_NE(text.find("le=\"0.002\""), std::string::npos) << "the 2 ms bound the alert reads";

  // The same lines through the runtime's HTTP endpoint.
  ASSERT_GT(runtime_->metrics_port(), 0);
  const std::string scraped = http(runtime_->metrics_port(), "GET /metrics HTTP/1.1\r\n\r\n");
  EXPECT_TRUE(
      has_line(scraped, "grpc_server_handled_total" + grpc_labels("OK", "GetEnvSpec") + " 2"))
      << scraped;
}

TEST_F(RpcMetricsTest, CountsAStreamOnceWhenItEndsAndItsEnvironmentSteps) {
  std::string id;
  {
    grpc::ClientContext c;
    sv1::CreateEnvRequest r;
    sv1::CreateEnvResponse out;
    r.set_robot(common::v1::ROBOT_FETCH);
    r.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    r.set_seed(1);
    r.set_count(2);
    ASSERT_TRUE(stub_->CreateEnv(&c, r, &out).ok());
    id = out.env_id();
  }
  grpc::ClientContext c;
  auto stream = stub_->StreamRollout(&c);
  sv1::StreamRolloutRequest r;
  r.set_env_id(id);
  ASSERT_TRUE(stream->Write(r));
  r.mutable_reset()->set_env_id(id);
  ASSERT_TRUE(stream->Write(r));
  sv1::StreamRolloutResponse out;
  ASSERT_TRUE(stream->Read(&out));
  for (int t = 0; t < 3; ++t) {
    sv1::StreamRolloutRequest s;
    s.mutable_step()->set_env_id(id);
    for (int k = 0; k < 2; ++k) {
      auto* a = s.mutable_step()->add_actions();
      a->set_index(k);
      a->mutable_goal()->set_x_m(1.3);
      a->mutable_goal()->set_y_m(0.7);
      a->mutable_goal()->set_z_m(0.45);
      a->set_objective(sv1::OBJECTIVE_TASK);
    }
    ASSERT_TRUE(stream->Write(s));
    ASSERT_TRUE(stream->Read(&out));
  }
  stream->WritesDone();
  ASSERT_TRUE(stream->Finish().ok());

  const std::string text = metrics_.render();
  EXPECT_TRUE(has_line(
      text, "grpc_server_handled_total" + grpc_labels("OK", "StreamRollout", "bidi_stream") + " 1"))
      << text;
  EXPECT_TRUE(has_line(text, "pnp_env_steps_total 6")) << text;
}

TEST_F(RpcMetricsTest, UnregisteredMethodsShareOneLabel) {
  // A PolicyService call on the simulation server: gRPC answers UNIMPLEMENTED, and the
  // client-chosen method name must not become a label value.
  auto policy = pnp::policy::v1::PolicyService::NewStub(channel_);
  grpc::ClientContext c;
  pnp::policy::v1::PredictRequest r;
  pnp::policy::v1::PredictResponse out;
  ASSERT_EQ(policy->Predict(&c, r, &out).error_code(), grpc::StatusCode::UNIMPLEMENTED);
  const std::string text = metrics_.render();
  EXPECT_NE(text.find("grpc_server_handled_total{grpc_code=\"Unimplemented\",grpc_method="
                      "\"unregistered\",grpc_service=\"unregistered\""),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("PolicyService"), std::string::npos);
}

}  // namespace
}  // namespace pnp::services
