#include "sim/scripted_evaluation.h"

#include <algorithm>
#include <cmath>

#include "common/rng.h"
#include "common/thread_pool.h"
#include "common/validate.h"
#include "sim/subtask_policy.h"
#include "sim/world_model.h"

namespace pnp::sim {
namespace {

void wilson_interval(double successes, double n, double& low, double& high) {
  constexpr double z = 1.959963984540054;
  const double p = successes / n;
  const double denom = 1 + z * z / n;
  const double centre = (p + z * z / (2 * n)) / denom;
  const double half = z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom;
  low = std::max(0.0, centre - half);
  high = std::min(1.0, centre + half);
}

ScriptedEvalReport summarise(const std::vector<EpisodeOutcome>& outcomes) {
  ScriptedEvalReport r;
  const double n = static_cast<double>(outcomes.size());
  double successes = 0, steps = 0, steps_sq = 0, distance = 0;
  for (std::size_t i = 0; i < outcomes.size(); ++i) {
    const EpisodeOutcome& o = outcomes[i];
    successes += o.success ? 1 : 0;
    steps += o.active_steps;
    steps_sq += static_cast<double>(o.active_steps) * o.active_steps;
    distance += o.final_distance_m;
    r.env_steps += o.env_steps;
    r.physics_faults += o.physics_fault() ? 1 : 0;
    if (!o.success) {
      r.failed_episodes.push_back(static_cast<int>(i));
      const auto first = std::find(o.subtask_done.begin(), o.subtask_done.end(), false);
      if (first == o.subtask_done.end()) {
        ++r.failed_after_all_done;
      } else {
        ++r.failed_in_subtask[static_cast<std::size_t>(first - o.subtask_done.begin())];
      }
    }
    for (std::size_t k = 0; k < kNumSubtasks; ++k) {
      r.subtask_success_rate[k] += o.subtask_done[k] ? 1 : 0;
      r.subtask_mean_steps[k] += o.subtask_steps[k];
    }
  }
  r.episodes = static_cast<int>(outcomes.size());
  r.success_rate = successes / n;
  wilson_interval(successes, n, r.success_ci95_low, r.success_ci95_high);
  r.mean_steps = steps / n;
  r.std_steps = std::sqrt(std::max(0.0, steps_sq / n - r.mean_steps * r.mean_steps));
  r.mean_final_distance_m = distance / n;
  for (std::size_t k = 0; k < kNumSubtasks; ++k) {
    r.subtask_success_rate[k] /= n;
    r.subtask_mean_steps[k] /= n;
  }
  return r;
}

}  // namespace

ScriptedEvalReport evaluate_pipeline(const EnvFactory& envs,
                                     const std::array<const SubtaskPolicy*, kNumSubtasks>& experts,
                                     long long episodes, std::uint64_t seed, ThreadPool& pool) {
  require_positive(episodes, "episodes");
  const auto count = static_cast<std::size_t>(episodes);
  const std::size_t workers = std::min(pool.size(), count);
  std::vector<EpisodeOutcome> outcomes(count);
  // Worker w runs episodes w, w + workers, ... on its own environment and policies.
  pool.parallel_for(workers, [&](std::size_t w) {
    const auto env = envs.make();
    std::array<std::unique_ptr<SubtaskPolicy>, kNumSubtasks> own;
    SubtaskPolicies policies{};
    for (std::size_t k = 0; k < kNumSubtasks; ++k) {
      own[k] = experts[k]->clone();
      policies[k] = own[k].get();
    }
    for (std::size_t i = w; i < count; i += workers) {
      outcomes[i] = run_pipeline_episode(*env, policies, derive_seed(seed, i));
    }
  });
  ScriptedEvalReport report = summarise(outcomes);
  report.robot = envs.robot();
  report.object = envs.object();
  report.world = envs.profile();
  report.actuation = envs.actuation();
  report.seed = seed;
  return report;
}

ScriptedEvalReport evaluate_scripted(Robot robot, ObjectShape object, long long episodes,
                                     std::uint64_t seed, std::size_t threads, WorldProfile world) {
  require_positive(episodes, "episodes");
  ThreadPool pool(threads);
  const ScriptedPolicy scripted;
  return evaluate_pipeline(LocalEnvFactory(WorldModel::load(robot, object, world)),
                           {&scripted, &scripted, &scripted}, episodes, seed, pool);
}

}  // namespace pnp::sim
