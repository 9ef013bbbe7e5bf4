#pragma once
// N environments of one world, stepped in parallel on a thread pool. Environment i is
// reset from derive_seed(seed, i), and each environment's trajectory depends only on its
// own seed and actions, so results are bit-identical at any thread count.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "common/thread_pool.h"
#include "sim/pick_place_env.h"

namespace pnp::sim {

class VecEnv {
 public:
  // num_envs must be positive; threads == 0 means one per hardware thread.
  VecEnv(std::shared_ptr<const WorldModel> world, long long num_envs, std::size_t threads = 0);

  std::size_t size() const { return envs_.size(); }
  std::size_t threads() const { return pool_.size(); }
  PickPlaceEnv& env(std::size_t i) { return envs_.at(i); }
  const PickPlaceEnv& env(std::size_t i) const { return envs_.at(i); }

  void reset(std::uint64_t seed);

  // actions: size() x 4, goals: size() x 3 (row-major), objectives and results: size().
  // Every input is validated before any environment steps: a refused call changes
  // nothing. An environment whose episode is over is reset from its own random stream
  // (auto-reset), so the batch never stalls.
  void step(std::span<const double> actions, std::span<const double> goals,
            std::span<const Objective> objectives, std::span<StepResult> results);

  // Runs fn(i, env) for every environment on the pool.
  void for_each(const std::function<void(std::size_t, PickPlaceEnv&)>& fn);

 private:
  std::vector<PickPlaceEnv> envs_;
  std::vector<std::uint64_t> next_seeds_;
  ThreadPool pool_;
};

}  // namespace pnp::sim
