#pragma once
// One training episode for a subtask expert: the subtasks before it run first (the
// prefix: scripted experts, or the learned experts it will follow when composed), then
// the expert acts with exploration until its predicate fires, its step cap, or the
// episode's end. The segment is what the replay stores; every step taken,
// prefix included, is counted. The suffix is not run in training: it produces no data
// for this expert (evaluation runs it).

#include <cstdint>
#include <vector>

#include "common/rng.h"
#include "rl/ddpg_her_agent.h"
#include "rl/segment_replay.h"
#include "sim/environment.h"
#include "sim/scripted_pipeline.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

struct ExplorationNoise {
  double gaussian_sigma = 0.2;
  double random_probability = 0.3;
  bool random_gripper = false;  // include the gripper in the uniformly random actions
  bool explore_gripper = true;  // false when the gripper command is scripted
};

struct SubtaskEpisode {
  std::vector<Transition> segment;
  int prefix_steps = 0;
  int env_steps = 0;  // prefix + segment
  bool subtask_done = false;
};

// The subtask's actions come from `expert` (any policy); exploration noise is added
// unless `noise` is null (demonstrations). `prefix` runs the subtasks before it (its
// entries from `subtask` on are not used); the prefix acts without noise.
SubtaskEpisode run_subtask_episode(sim::Environment& env, sim::Subtask subtask,
                                   const sim::SubtaskPolicies& prefix, sim::SubtaskPolicy& expert,
                                   const ExplorationNoise* noise, std::uint64_t episode_seed,
                                   Rng& noise_rng);

// One end-to-end training episode: the policy acts on the episode goal for all its steps
// (objective "task"); the whole episode is one segment.
SubtaskEpisode run_end_to_end_episode(sim::Environment& env, sim::SubtaskPolicy& policy,
                                      const ExplorationNoise& noise, std::uint64_t episode_seed,
                                      Rng& noise_rng);

// Adds exploration to a deterministic action: with probability random_probability a
// uniform random motion (and gripper command, if random_gripper), otherwise Gaussian
// noise on every dimension; clipped to [-1, 1].
sim::Action explore(const sim::Action& action, const ExplorationNoise& noise, Rng& rng);

}  // namespace pnp::rl
