#include "sim/vec_env.h"

#include <string>

#include "common/error.h"
#include "common/rng.h"
#include "common/validate.h"

namespace pnp::sim {
namespace {

std::size_t checked_count(long long num_envs) {
  require_positive(num_envs, "num_envs");
  return static_cast<std::size_t>(num_envs);
}

}  // namespace

VecEnv::VecEnv(std::shared_ptr<const WorldModel> world, long long num_envs, std::size_t threads)
    : next_seeds_(checked_count(num_envs), 0), pool_(threads) {
  envs_.reserve(next_seeds_.size());
  for (std::size_t i = 0; i < next_seeds_.size(); ++i) envs_.emplace_back(world);
}

void VecEnv::reset(std::uint64_t seed) {
  for (std::size_t i = 0; i < envs_.size(); ++i) next_seeds_[i] = derive_seed(seed, i);
  pool_.parallel_for(envs_.size(), [&](std::size_t i) {
    envs_[i].reset(next_seeds_[i]);
    next_seeds_[i] = derive_seed(next_seeds_[i], 1);
  });
}

void VecEnv::for_each(const std::function<void(std::size_t, PickPlaceEnv&)>& fn) {
  pool_.parallel_for(envs_.size(), [&](std::size_t i) { fn(i, envs_[i]); });
}

void VecEnv::step(std::span<const double> actions, std::span<const double> goals,
                  std::span<const Objective> objectives, std::span<StepResult> results) {
  const std::size_t n = envs_.size();
  require_finite_vector(actions, n * kActionSize, "actions");
  require_finite_vector(goals, n * kGoalSize, "goals");
  require_size(objectives.size(), n, "objectives");
  require_size(results.size(), n, "results");
  for (std::size_t i = 0; i < n; ++i) {
    const int value = static_cast<int>(objectives[i]);
    if (value < 0 || value > static_cast<int>(Objective::kTask)) {
      throw_invalid_argument("objectives[" + std::to_string(i) + "]",
                             "approach, manipulate, retract or task", std::to_string(value));
    }
  }
  pool_.parallel_for(n, [&](std::size_t i) {
    if (envs_[i].needs_reset()) {
      envs_[i].reset(next_seeds_[i]);
      next_seeds_[i] = derive_seed(next_seeds_[i], 1);
    }
    results[i] = envs_[i].step(actions.subspan(i * kActionSize, kActionSize),
                               goals.subspan(i * kGoalSize, kGoalSize), objectives[i]);
  });
}

}  // namespace pnp::sim
