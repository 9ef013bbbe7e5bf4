#include "rl/end_to_end_evaluation.h"

#include <algorithm>
#include <numeric>
#include <vector>

#include "common/rng.h"

namespace pnp::rl {

EndToEndReport evaluate_end_to_end(const sim::EnvFactory& envs, const sim::SubtaskPolicy& policy,
                                   int episodes, std::uint64_t seed, ThreadPool& pool) {
  const auto count = static_cast<std::size_t>(episodes);
  const std::size_t workers = std::min(pool.size(), count);
  std::vector<char> success(count, 0);
  std::vector<long long> steps(count, 0);  // a fault ends an episode early
  pool.parallel_for(workers, [&](std::size_t w) {
    const auto made = envs.make();
    sim::Environment& env = *made;
    const auto own = policy.clone();
    for (std::size_t i = w; i < count; i += workers) {
      env.reset(derive_seed(seed, i));
      sim::StepResult last;
      while (!env.needs_reset()) {
        const sim::Goal goal = env.episode_goal();
        last = env.step(own->act(sim::Subtask::kRetract, env.observation(), goal, env.task_state()),
                        goal, sim::Objective::kTask);
        ++steps[i];
        if (last.fault != sim::PhysicsFault::kNone) break;
      }
      success[i] = last.fault == sim::PhysicsFault::kNone && last.task_success ? 1 : 0;
    }
  });
  return {static_cast<double>(std::count(success.begin(), success.end(), 1)) /
              static_cast<double>(count),
          std::accumulate(steps.begin(), steps.end(), 0LL)};
}

}  // namespace pnp::rl
