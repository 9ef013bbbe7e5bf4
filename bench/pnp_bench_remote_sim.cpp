// pnp-bench-remote-sim: what running rollouts on a simulation service costs, against the
// same work in process, measured in the same run. The service is SimulationService in
// this process, reached over loopback TCP through RemoteEnvFactory, exactly as
// `pnp-train-server --sim-address` reaches one; on a 2-core machine client and service
// share the cores, so this is the per-step overhead of the stream, not a scale-out gain.
//   rollouts: scripted episodes on `--workers` parallel environments, env steps/s;
//   training: an approach expert trained to a fixed step cap (train_role, the service's
//             code path), env steps (training + evaluation) per second and wall time.

#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "clients/sim_client/remote_env_factory.h"
#include "common/rng.h"
#include "common/thread_pool.h"
#include "services/common/server_runtime.h"
#include "services/sim/sim_service.h"
#include "sim/scripted_pipeline.h"
#include "tools/common/cli.h"
#include "training/role_training.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace pnp;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Scripted episodes on `workers` environments in parallel; env steps per second.
double rollout_steps_per_s(const sim::EnvFactory& envs, int workers, int episodes) {
  ThreadPool pool(static_cast<std::size_t>(workers));
  std::vector<long long> steps(static_cast<std::size_t>(workers), 0);
  const auto start = Clock::now();
  pool.parallel_for(static_cast<std::size_t>(workers), [&](std::size_t w) {
    const auto env = envs.make();
    for (int e = 0; e < episodes; ++e) {
      sim::run_scripted_episode(*env, derive_seed(w, static_cast<std::uint64_t>(e)));
      steps[w] += env->elapsed_steps();
    }
  });
  const double elapsed = seconds_since(start);
  long long total = 0;
  for (long long s : steps) total += s;
  return static_cast<double>(total) / elapsed;
}

struct TrainingRun {
  double wall_s = 0;
  long long env_steps = 0;  // training and evaluation
  training::Blob checkpoint;
};

TrainingRun train(const training::EnvironmentSource& environments, long long max_steps,
                  std::size_t threads) {
  training::TrainingSpec spec;
  spec.role = "approach";
  spec.algorithm = "ddpg_her";
  spec.seed = 1;
  spec.stop.max_steps = max_steps;
  spec.stop.eval_interval_steps = 500;
  spec.stop.eval_episodes = 20;
  spec.stop.target_success = 1.0;  // rarely twice: the run goes to its cap
  training::TrainingHooks hooks;
  hooks.threads = threads;
  hooks.environments = environments;
  const auto start = Clock::now();
  const auto out = training::train_role(spec, {}, hooks, "bench");
  return {seconds_since(start), out.result.train_env_steps + out.result.eval_env_steps,
          out.checkpoint};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Rollouts and training on a simulation service vs in process",
               "pnp-bench-remote-sim"};
  bool json = false;
  int workers = 2, episodes = 40;
  long long train_steps = 3000;
  app.add_flag("--json", json, "print JSON only");
  app.add_option("--workers", workers, "parallel environments")->check(CLI::Range(1, 64));
  app.add_option("--episodes", episodes, "scripted episodes per worker")
      ->check(CLI::Range(1, 10000));
  app.add_option("--train-steps", train_steps, "training step cap")
      ->check(CLI::Range(100, 1000000));
  return tools::run_tool(app, argc, argv, [&] {
    services::MetricsRegistry metrics;
    services::SimServiceImpl service(&metrics);
    services::ServerRuntime server(
        {"127.0.0.1:0", 4 << 20, {&service}, {"pnp.sim.v1.SimulationService"}});
    const std::vector<std::string> addresses{"127.0.0.1:" + std::to_string(server.port())};
    const sim::LocalEnvFactory local(
        sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
    const sim_client::RemoteEnvFactory remote(addresses, sim::Robot::kFetch,
                                              sim::ObjectShape::kBlock);

    rollout_steps_per_s(local, workers, 2);  // warm-up: page in, connect
    rollout_steps_per_s(remote, workers, 2);
    const double local_rollout = rollout_steps_per_s(local, workers, episodes);
    const double remote_rollout = rollout_steps_per_s(remote, workers, episodes);

    const auto threads = static_cast<std::size_t>(workers);
    const TrainingRun local_training = train({}, train_steps, threads);
    const TrainingRun remote_training = train(
        [&](sim::Robot robot, sim::ObjectShape object, sim::WorldProfile world,
            sim::Actuation actuation) {
          return std::make_unique<sim_client::RemoteEnvFactory>(addresses, robot, object, world,
                                                                actuation);
        },
        train_steps, threads);
    server.shutdown(std::chrono::milliseconds(500));

    const double local_rate = static_cast<double>(local_training.env_steps) / local_training.wall_s;
    const double remote_rate =
        static_cast<double>(remote_training.env_steps) / remote_training.wall_s;
    const nlohmann::json out = {
        {"workers", workers},
        {"rollout_steps_per_s_in_process", local_rollout},
        {"rollout_steps_per_s_remote", remote_rollout},
        {"rollout_ratio", remote_rollout / local_rollout},
        {"training_env_steps", local_training.env_steps},
        {"training_wall_s_in_process", local_training.wall_s},
        {"training_wall_s_remote", remote_training.wall_s},
        {"training_steps_per_s_in_process", local_rate},
        {"training_steps_per_s_remote", remote_rate},
        {"training_ratio", remote_rate / local_rate},
        {"identical_weights", local_training.checkpoint == remote_training.checkpoint},
    };
    std::cout << (json ? out.dump() : out.dump(2)) << "\n";
  });
}
