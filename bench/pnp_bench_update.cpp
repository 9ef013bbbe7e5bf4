// pnp-bench-update: DDPG+HER gradient updates per second (batch 256, 3 x 256 actor and
// critic, Adam, Polyak) at 1 and 2 update threads, with the same update in PyTorch on
// the CPU run in the same invocation as the peer (bench/torch_ddpg_update.py, Debian's
// python3-torch on OpenBLAS, best of 1 and 2 PyTorch threads x 1 and 2 OpenBLAS threads),
// and the fraction of this machine's measured GEMM peak the update reaches. The GEMM path
// (nn/gemm_path.h) is the process's: PNP_GEMM=avx512|avx2|openblas times one path.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/rng.h"
#include "common/validate.h"
#include "nn/cpu_features.h"
#include "nn/gemm.h"
#include "nn/gemm_path.h"
#include "rl/ddpg_her_agent.h"
#include "tools/common/cli.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace pnp;

// A replay-like batch of random (but fixed) inputs.
rl::SampledBatch random_batch(int n, Rng& rng) {
  rl::SampledBatch b;
  auto fill = [&](std::vector<float>& v, std::size_t size, double scale) {
    v.resize(size);
    for (float& x : v) x = static_cast<float>(rng.uniform(-scale, scale));
  };
  const auto un = static_cast<std::size_t>(n);
  fill(b.observation, un * sim::kObservationSize, 1.0);
  fill(b.next_observation, un * sim::kObservationSize, 1.0);
  fill(b.goal, un * sim::kGoalSize, 1.0);
  fill(b.action, un * sim::kActionSize, 1.0);
  fill(b.reward, un, 0.5);
  for (float& r : b.reward) r = -std::abs(r);
  b.done.assign(un, 0.0f);
  return b;
}

// FLOPs of one update: 2 x multiply-adds of every GEMM (forward 1x, backward 2x with
// weight and input gradients, 1x when only one of them is needed).
double update_flops(const rl::DdpgHerConfig& c) {
  auto mlp_macs = [&](int in, int out) {
    double macs = 0;
    int prev = in;
    for (int h : c.hidden) {
      macs += static_cast<double>(prev) * h;
      prev = h;
    }
    return macs + static_cast<double>(prev) * out;
  };
  const double actor = mlp_macs(rl::kPolicyInputs, sim::kActionSize);
  const double critic = mlp_macs(rl::kPolicyInputs + sim::kActionSize, 1);
  // target actor fwd + target critic fwd + critic fwd/bwd(weights) + actor fwd
  // + critic fwd + critic bwd(inputs only) + actor bwd(weights and inputs of hidden)
  const double macs = actor + critic + 2 * critic + actor + critic + critic + 2 * actor;
  return 2.0 * macs * c.batch_size;
}

// The same GEMM path the update uses (the process's kernel, or OpenBLAS on one thread), at
// the update's shape.
double gemm_peak_gflops() {
  nn::Matrix a = nn::Matrix::Random(256, 256), b = nn::Matrix::Random(256, 256), c(256, 256);
  double best = 1e300;
  for (int r = 0; r < 30; ++r) {
    const auto t0 = Clock::now();
    nn::gemm(false, false, 1.0f, a.data(), 256, 256, b.data(), 256, 256, 0.0f, c);
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  volatile float sink = c(0, 0);
  (void)sink;
  return 2.0 * 256 * 256 * 256 / best / 1e9;
}

// Runs the PyTorch peer and returns its JSON, or an object with an "error".
nlohmann::json run_torch_peer(const std::string& python, const std::string& script, int updates) {
  const std::string command = python + " " + script + " " + std::to_string(updates) + " 2>&1";
  std::FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {{"error", "could not start " + python}};
  std::string output;
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe)) output += buffer;
  const int status = pclose(pipe);
  // The peer's result is its last line.
  while (!output.empty() && output.back() == '\n') output.pop_back();
  const std::string last =
      output.substr(output.rfind('\n') == std::string::npos ? 0 : output.rfind('\n') + 1);
  if (status != 0 || last.empty() || last.front() != '{') {
    return {
        {"error",
         "the PyTorch peer failed (install python3-torch: scripts/install-bench-deps): " + output}};
  }
  return nlohmann::json::parse(last);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Benchmark DDPG+HER updates against PyTorch", "pnp-bench-update"};
  int updates = 200, rounds = 3;
  bool json = false, skip_torch = false;
  std::string python = "/usr/bin/python3", script = PNP_TORCH_PEER_SCRIPT;
  app.add_option("--updates", updates, "timed updates")->capture_default_str();
  app.add_option("--rounds", rounds, "alternating rounds of ours and the peer; best kept")
      ->capture_default_str();
  app.add_flag("--json", json);
  app.add_flag("--no-torch", skip_torch, "skip the PyTorch peer");
  app.add_option("--python", python, "interpreter with Debian's python3-torch")
      ->capture_default_str();
  app.add_option("--torch-script", script)->capture_default_str();
  return tools::run_tool(app, argc, argv, [&] {
    require_positive(updates, "--updates");
    require_positive(rounds, "--rounds");
    const nn::GemmPath path = nn::active_gemm_path();  // refuses a bad PNP_GEMM first
    rl::DdpgHerConfig config;                          // batch 256, 3 x 256: the original's
    // Ours at one and two update threads (the same weights either way), like the peer's
    // thread settings; the best is compared.
    constexpr std::array<std::size_t, 2> kThreads{1, rl::kUpdatePartitions};
    std::vector<std::unique_ptr<rl::DdpgHerAgent>> agents;
    Rng rng(1);
    const rl::SampledBatch batch = random_batch(config.batch_size, rng);
    for (std::size_t threads : kThreads) {
      Rng init(2);
      agents.push_back(std::make_unique<rl::DdpgHerAgent>(config, init, threads));
      for (int i = 0; i < 20; ++i) agents.back()->update(batch);  // warm-up
    }
    // Rounds alternate ours and the peer, each side's best round kept: this machine is
    // shared, and load that comes and goes then hits both sides alike.
    std::array<double, kThreads.size()> ups_by_threads{};
    nlohmann::json torch_best;
    for (int round = 0; round < rounds; ++round) {
      for (std::size_t k = 0; k < kThreads.size(); ++k) {
        const auto t0 = Clock::now();
        for (int i = 0; i < updates; ++i) {
          agents[k]->update(batch);
          agents[k]->update_targets(1);
        }
        ups_by_threads[k] = std::max(
            ups_by_threads[k], updates / std::chrono::duration<double>(Clock::now() - t0).count());
      }
      if (skip_torch) continue;
      const nlohmann::json torch = run_torch_peer(python, script, updates);
      if (!torch.contains("updates_per_s")) {
        torch_best = torch;  // the error, reported below
        break;
      }
      if (torch_best.empty() ||
          torch["updates_per_s"].get<double>() > torch_best["updates_per_s"].get<double>())
        torch_best = torch;
    }
    const std::size_t best = ups_by_threads[1] >= ups_by_threads[0] ? 1 : 0;
    const double ups = ups_by_threads[best];
    nlohmann::json by_threads = nlohmann::json::object();
    for (std::size_t k = 0; k < kThreads.size(); ++k)
      by_threads[std::to_string(kThreads[k])] = ups_by_threads[k];
    const double peak = gemm_peak_gflops();
    const double gflops = update_flops(config) * ups / 1e9;
    nlohmann::json out = {
        {"gemm_path", nn::gemm_path_name(path)},
        {"cpu_features", nn::describe(nn::detect_cpu_features())},
        {"updates_per_s", ups},
        {"ms_per_update", 1000.0 / ups},
        {"rounds", rounds},
        {"update_gflop", update_flops(config) / 1e9},
        {"achieved_gflops", gflops},
        {"gemm_peak_gflops_1_thread", peak},
        {"updates_per_s_by_threads", by_threads},
        {"update_threads", kThreads[best]},
        // Against the peak of the cores the best setting used.
        {"fraction_of_gemm_peak", gflops / (peak * static_cast<double>(kThreads[best]))}};
    if (!skip_torch) {
      out["torch"] = torch_best;
      if (torch_best.contains("updates_per_s")) {
        out["torch_updates_per_s"] = torch_best["updates_per_s"];
        out["ratio"] = ups / torch_best["updates_per_s"].get<double>();
      }
    }
    std::cout << (json ? out.dump() : out.dump(2)) << "\n";
  });
}
