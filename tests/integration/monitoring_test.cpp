// Integration: a real Prometheus (Debian's) on loopback scrapes the real servers' /metrics
// with deploy/monitoring's alert rules loaded; its HTTP API then shows the platform's
// series with non-zero values, every rule evaluates without error, and every query of the
// Grafana dashboard parses and names only series the platform exports.
#include <arpa/inet.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"
#include "tests/integration/metrics_scrape.h"

namespace pnp::integration {
namespace {

namespace sv1 = pnp::sim::v1;

// A loopback port free now (Prometheus cannot report the port it took for :0).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0)
    port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

std::string url_encoded(const std::string& text) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (std::isalnum(byte) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += c;
    } else {
      out += '%';
      out += hex[byte >> 4];
      out += hex[byte & 15];
    }
  }
  return out;
}

// The JSON body of a Prometheus API answer (null on no answer).
nlohmann::json api(int port, const std::string& path) {
  const std::string response = http_get(port, path);
  const auto body = response.find("\r\n\r\n");
  if (body == std::string::npos) return nullptr;
  return nlohmann::json::parse(response.substr(body + 4), nullptr, false);
}

// A string member of an API object ("" when absent).
std::string text_of(const nlohmann::json& object, const char* key) {
  if (!object.is_object() || !object.contains(key)) return {};
  const nlohmann::json& member = object.at(key);
  return member.is_string() ? member.get<std::string>() : std::string();
}

nlohmann::json query(int port, const std::string& promql) {
  return api(port, "/api/v1/query?query=" + url_encoded(promql));
}

// The sum of an instant query's sample values (0 when it has none).
double query_sum(int port, const std::string& promql) {
  const nlohmann::json answer = query(port, promql);
  double sum = 0;
  if (text_of(answer, "status") == "success")
    for (const auto& sample : answer.at("data").at("result"))
      sum += std::stod(sample.at("value").at(1).get_ref<const std::string&>());
  return sum;
}

bool eventually(const std::function<bool()>& condition, std::chrono::seconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    if (condition()) return true;
    std::this_thread::sleep_for(250ms);
  }
  return condition();
}

std::vector<std::string> server(const std::string& binary, std::vector<std::string> args) {
  args.insert(args.begin(), std::string(PNP_BIN_DIR) + "/" + binary);
  for (const char* a : {"--address", "127.0.0.1:0", "--metrics-address", "127.0.0.1:0"})
    args.emplace_back(a);
  return args;
}

// One environment of the simulation service stepped once: pnp_env_steps_total becomes 1.
void step_once(int sim_port) {
  auto stub = sv1::SimulationService::NewStub(
      grpc::CreateChannel(loopback(sim_port), grpc::InsecureChannelCredentials()));
  grpc::ClientContext create_context, reset_context, step_context;
  sv1::CreateEnvRequest create;
  create.set_robot(common::v1::ROBOT_FETCH);
  create.set_object(common::v1::OBJECT_SHAPE_BLOCK);
  create.set_count(1);
  sv1::CreateEnvResponse created;
  ASSERT_TRUE(stub->CreateEnv(&create_context, create, &created).ok());
  sv1::ResetRequest reset;
  reset.set_env_id(created.env_id());
  sv1::ResetResponse state;
  ASSERT_TRUE(stub->Reset(&reset_context, reset, &state).ok());
  sv1::StepRequest step;
  step.set_env_id(created.env_id());
  auto* action = step.add_actions();
  *action->mutable_goal() = state.states(0).episode_goal();
  action->set_objective(sv1::OBJECTIVE_TASK);
  sv1::StepResponse stepped;
  ASSERT_TRUE(stub->Step(&step_context, step, &stepped).ok());
}

TEST(Monitoring, ARealPrometheusScrapesTheServersAndAnswersEveryDashboardQuery) {
  TempDir dir("monitoring");
  const std::string db = dir.file("pnp.db");
  {
    store::RunStore store(db);
    store::import_hierarchy(store, PNP_SOURCE_DIR "/tests/data/panda_block", "panda", "block");
  }
  ChildProcess sim("sim", server("pnp-sim-server", {}), dir.path());
  ChildProcess inference("inference", server("pnp-inference-server", {"--db", db}), dir.path());
  ChildProcess train(
      "train", server("pnp-train-server", {"--role", "approach", "--threads", "1", "--db", db}),
      dir.path());
  const int sim_port = sim.port();
  ASSERT_GT(sim_port, 0) << sim.diagnostics();
  ASSERT_GT(inference.port(), 0) << inference.diagnostics();
  ASSERT_GT(train.port(), 0) << train.diagnostics();
  ASSERT_NO_FATAL_FAILURE(step_once(sim_port));

  const int prometheus_port = free_port();
  const std::string config = dir.file("prometheus.yml");
  {
    std::ofstream out(config);
    out << "global: {scrape_interval: 1s, evaluation_interval: 1s}\n"
        << "rule_files: ['" << PNP_SOURCE_DIR << "/deploy/monitoring/alerts.yml']\n"
        << "scrape_configs:\n  - job_name: pnp\n    static_configs:\n"
        << "      - targets: ['127.0.0.1:" << metrics_port(sim) << "']\n"
        << "        labels: {service: sim}\n"
        << "      - targets: ['127.0.0.1:" << metrics_port(inference) << "']\n"
        << "        labels: {service: inference}\n"
        << "      - targets: ['127.0.0.1:" << metrics_port(train) << "']\n"
        << "        labels: {service: train, role: approach}\n";
  }
  ChildProcess prometheus(
      "prometheus",
      {PNP_PROMETHEUS, "--config.file=" + config, "--storage.tsdb.path=" + dir.file("tsdb"),
       "--web.listen-address=127.0.0.1:" + std::to_string(prometheus_port)},
      dir.path());

  // The platform's counters, scraped: the step taken and the RPCs that took it.
  EXPECT_TRUE(
      eventually([&] { return query_sum(prometheus_port, "pnp_env_steps_total") >= 1; }, 60s))
      << prometheus.diagnostics();
  EXPECT_GE(query_sum(prometheus_port,
                      "sum(grpc_server_handled_total{grpc_service=\"pnp.sim.v1.SimulationService\","
                      "grpc_method=\"Step\",grpc_code=\"OK\"})"),
            1.0);
  EXPECT_TRUE(eventually(
      [&] { return query_sum(prometheus_port, "count(up{job=\"pnp\"} == 1)") == 3; }, 30s));

  // Every alert rule loads and evaluates without error.
  EXPECT_TRUE(eventually(
      [&] {
        const nlohmann::json rules = api(prometheus_port, "/api/v1/rules");
        if (!rules.is_object() || !rules.contains("data")) return false;
        const auto& groups = rules.at("data").at("groups");
        if (groups.empty()) return false;
        for (const auto& group : groups)
          for (const auto& rule : group.at("rules"))
            if (text_of(rule, "health") != "ok") return false;
        return true;
      },
      30s))
      << api(prometheus_port, "/api/v1/rules").dump();

  // Every dashboard query parses, and names only series the platform exports: the servers
  // scraped here, or the gateway's (pinned by GatewayMetrics' own test).
  std::set<std::string> exported;
  const nlohmann::json names = api(prometheus_port, "/api/v1/label/__name__/values");
  ASSERT_TRUE(names.is_object() && names.contains("data")) << names.dump();
  for (const auto& name : names.at("data")) exported.insert(name.get_ref<const std::string&>());
  std::ifstream file(PNP_SOURCE_DIR "/deploy/monitoring/grafana-dashboard.json");
  const auto dashboard = nlohmann::json::parse(file);
  const std::regex metric_name(R"(\b((?:pnp|grpc_server)_[a-z_]+)\b)");
  int queries = 0;
  for (const auto& panel : dashboard.at("panels")) {
    for (const auto& target : panel.at("targets")) {
      std::string expr = target.at("expr").get_ref<const std::string&>();
      expr = std::regex_replace(expr, std::regex(R"(\$__rate_interval)"), "1m");
      const nlohmann::json answer = query(prometheus_port, expr);
      EXPECT_TRUE(text_of(answer, "status") == "success")
          << panel.at("title") << ": " << expr << "\n"
          << answer.dump();
      for (std::sregex_iterator m(expr.begin(), expr.end(), metric_name), end; m != end; ++m) {
        const std::string name = (*m)[1];
        EXPECT_TRUE(exported.contains(name) || name.starts_with("pnp_gateway_"))
            << panel.at("title") << " queries " << name << ", which no server exports";
      }
      ++queries;
    }
  }
  EXPECT_GT(queries, 10);
}

}  // namespace
}  // namespace pnp::integration
