// pnp-bench-inference: Predict latency and throughput over loopback TCP, beside an empty
// unary RPC (Ping) on the same server in the same run: the gRPC floor. The served
// hierarchy has the real network sizes (experts 3 x 256, choreographer 128-128-LSTM 32),
// randomly initialised: latency does not depend on the weights.
//   p50_ratio = Predict p50 / Ping p50 with one client.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "common/percentile.h"
#include "common/validate.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "sim/pick_place_env.h"
#include "store/run_store.h"
#include "tools/common/cli.h"

namespace {

using namespace pnp;
using Clock = std::chrono::steady_clock;
namespace pv1 = policy::v1;

void promote_random_hierarchy(store::RunStore& store) {
  auto save = [&](const std::string& role, const std::vector<std::uint8_t>& blob) {
    const auto run = store.create_run(
        {role, role == "hlc" ? "a3c" : "ddpg_her", "fetch", "block", 0, "{}", "", std::nullopt});
    store.promote(store.save_checkpoint(run.id, 0, 0, blob).id);
  };
  for (const char* role : {"approach", "manipulate", "retract"}) {
    rl::DdpgHerConfig config;  // 3 x 256
    Rng rng(1);
    rl::DdpgHerAgent agent(config, rng);
    save(role, rl::save_expert({role, "ddpg_her", "fetch", "block", "paper", config.hidden,
                                config.hidden_activation, true, 200, 5, 0.01, 0, 0, 0, "bench"},
                               agent.actor(), nullptr, agent.observation_normalizer(),
                               agent.goal_normalizer()));
  }
  rl::ChoreographerNet net({});
  Rng rng(2);
  net.initialise(rng);
  save("hlc",
       rl::save_choreographer({"fetch", "block", "paper", net.spec(), 0, 0, 0, "bench"}, net));
}

struct Latencies {
  std::vector<double> us;
  double wall_s = 0;
  double percentile(double q) const { return pnp::percentile(us, q); }
  double qps() const { return static_cast<double>(us.size()) / wall_s; }
};

// `clients` threads, each with its own channel, each making `calls` calls of `call`.
template <typename Call>
Latencies measure(int port, int clients, int calls, Call call) {
  std::vector<std::vector<double>> per_client(static_cast<std::size_t>(clients));
  const auto start = Clock::now();
  {
    std::vector<std::jthread> threads;
    for (int c = 0; c < clients; ++c) {
      threads.emplace_back([&, c] {
        auto stub = pv1::PolicyService::NewStub(grpc::CreateChannel(
            "127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials()));
        for (int w = 0; w < 50; ++w) call(*stub);  // connect and warm up
        auto& out = per_client[static_cast<std::size_t>(c)];
        out.reserve(static_cast<std::size_t>(calls));
        for (int i = 0; i < calls; ++i) {
          const auto t0 = Clock::now();
          call(*stub);
          out.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        }
      });
    }
  }
  Latencies l;
  l.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  for (auto& v : per_client) l.us.insert(l.us.end(), v.begin(), v.end());
  return l;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Predict latency over loopback against an empty RPC", "pnp-bench-inference"};
  int calls = 3000;
  bool json = false;
  app.add_option("--calls", calls, "timed calls per client")->capture_default_str();
  app.add_flag("--json", json, "print one JSON object");
  return tools::run_tool(app, argc, argv, [&] {
    require_positive(calls, "--calls");
    const auto dir = std::filesystem::temp_directory_path() /
                     ("pnp_bench_inference_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string db = (dir / "pnp.db").string();
    {
      store::RunStore store(db);
      promote_random_hierarchy(store);
    }
    services::PolicyServiceImpl service(db);
    services::ServerRuntime runtime(
        {"127.0.0.1:0", 4 << 20, {&service}, {"pnp.policy.v1.PolicyService"}});

    sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
    env.reset(1);
    pv1::PredictRequest request;
    for (int k = 0; k < sim::kObservationSize; ++k)
      request.mutable_observation()->add_values(env.observation()(k));
    request.mutable_goal()->set_x_m(env.episode_goal().x());
    request.mutable_goal()->set_y_m(env.episode_goal().y());
    request.mutable_goal()->set_z_m(env.episode_goal().z());
    auto predict = [&](pv1::PolicyService::Stub& stub) {
      grpc::ClientContext context;
      pv1::PredictResponse response;
      if (!stub.Predict(&context, request, &response).ok())
        throw std::runtime_error("Predict failed");
    };
    auto ping = [](pv1::PolicyService::Stub& stub) {
      grpc::ClientContext context;
      pv1::PingResponse response;
      if (!stub.Ping(&context, {}, &response).ok()) throw std::runtime_error("Ping failed");
    };
    // Interleave rounds so that load drift hits both alike; keep each one's best round.
    Latencies p1, f1, p8, f8;
    double best_ratio = 1e9;
    for (int round = 0; round < 3; ++round) {
      auto fr = measure(runtime.port(), 1, calls, ping);
      auto pr = measure(runtime.port(), 1, calls, predict);
      const double ratio = pr.percentile(0.5) / fr.percentile(0.5);
      if (ratio < best_ratio) {
        best_ratio = ratio;
        p1 = std::move(pr);
        f1 = std::move(fr);
      }
    }
    f8 = measure(runtime.port(), 8, calls / 4, ping);
    // Every request here is the same state, so runs the same expert: summed over the
    // experts, the counts show how requests were batched.
    auto total = [&] {
      serving::BatchStats sum;
      for (const auto& s : service.batch_stats()) {
        sum.requests += s.requests;
        sum.batches += s.batches;
        sum.largest_batch = std::max(sum.largest_batch, s.largest_batch);
      }
      return sum;
    };
    const auto before = total();
    p8 = measure(runtime.port(), 8, calls / 4, predict);
    const auto after = total();
    const double mean_batch_8_clients =
        static_cast<double>(after.requests - before.requests) /
        static_cast<double>(std::max<std::uint64_t>(1, after.batches - before.batches));
    runtime.shutdown(std::chrono::seconds(1));
    std::filesystem::remove_all(dir);

    const nlohmann::json out = {{"calls_per_client", calls},
                                {"predict_p50_us", p1.percentile(0.5)},
                                {"predict_p99_us", p1.percentile(0.99)},
                                {"floor_p50_us", f1.percentile(0.5)},
                                {"floor_p99_us", f1.percentile(0.99)},
                                {"p50_ratio", p1.percentile(0.5) / f1.percentile(0.5)},
                                {"qps_1_client", p1.qps()},
                                {"predict_8_clients_p50_us", p8.percentile(0.5)},
                                {"predict_8_clients_p99_us", p8.percentile(0.99)},
                                {"floor_8_clients_p50_us", f8.percentile(0.5)},
                                {"qps_8_clients", p8.qps()},
                                {"floor_qps_8_clients", f8.qps()},
                                {"mean_expert_batch_8_clients", mean_batch_8_clients},
                                {"largest_expert_batch", after.largest_batch}};
    std::cout << (json ? out.dump() : out.dump(2)) << "\n";
  });
}
