#pragma once
// Evaluates an end-to-end policy: it acts on the episode goal for all the episode's steps; success
// is read at the last step, from the object.

#include <memory>

#include "common/thread_pool.h"
#include "sim/env_factory.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

struct EndToEndReport {
  double success_rate = 0;
  long long env_steps = 0;
};

EndToEndReport evaluate_end_to_end(const sim::EnvFactory& envs, const sim::SubtaskPolicy& policy,
                                   int episodes, std::uint64_t seed, ThreadPool& pool);

}  // namespace pnp::rl
