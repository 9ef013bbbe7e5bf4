#include "rl/subtask_rollout.h"

namespace pnp::rl {

sim::Action explore(const sim::Action& action, const ExplorationNoise& noise, Rng& rng) {
  // The uniformly random action replaces the motion (xyz) only, unless random_gripper:
  // a random gripper command opens the fingers half the time and drops a carried
  // object, which made every retract episode a drop (measured: 0-6% task success after
  // 10k steps, against 99% at 4k with the same motion exploration and a scripted gripper).
  const bool random = rng.uniform() < noise.random_probability;
  sim::Action out;
  for (int k = 0; k < sim::kActionSize; ++k) {
    const bool uniform = random && (k < 3 || noise.random_gripper);
    out(k) = uniform ? rng.uniform(-1.0, 1.0) : action(k) + noise.gaussian_sigma * rng.normal();
  }
  return out.cwiseMax(-1.0).cwiseMin(1.0);
}

SubtaskEpisode run_subtask_episode(sim::Environment& env, sim::Subtask subtask,
                                   const sim::SubtaskPolicies& prefix, sim::SubtaskPolicy& expert,
                                   const ExplorationNoise* noise, std::uint64_t episode_seed,
                                   Rng& noise_rng) {
  SubtaskEpisode out;
  env.reset(episode_seed);
  for (sim::Subtask before : sim::kAllSubtasks) {
    if (before == subtask) break;
    sim::SubtaskPolicy& policy = *prefix[static_cast<std::size_t>(before)];
    const sim::Objective objective = sim::objective_of(before);
    for (int t = 0; t < sim::step_cap(before, env.episode_steps()) && !env.needs_reset(); ++t) {
      const sim::TaskState state = env.task_state();
      const sim::Goal goal = sim::objective_goal(objective, state);
      const auto r = env.step(policy.act(before, env.observation(), goal, state), goal, objective);
      ++out.prefix_steps;
      if (r.objective_done || r.fault != sim::PhysicsFault::kNone) break;
    }
  }
  out.env_steps = out.prefix_steps;
  const sim::Objective objective = sim::objective_of(subtask);
  for (int t = 0; t < sim::step_cap(subtask, env.episode_steps()) && !env.needs_reset(); ++t) {
    const sim::TaskState state = env.task_state();
    const sim::Goal goal = sim::objective_goal(objective, state);
    const sim::Observation observation = env.observation();
    sim::Action action = expert.act(subtask, observation, goal, state);
    if (noise) {
      const double gripper = action(3);
      action = explore(action, *noise, noise_rng);
      // A gripper the expert does not learn stays exactly as commanded.
      if (!noise->explore_gripper) action(3) = gripper;
    }
    const sim::StepResult r = env.step(action, goal, objective);
    ++out.env_steps;
    if (r.fault != sim::PhysicsFault::kNone) break;  // the transition is not physical: drop it
    out.segment.push_back({observation, action, goal, r.observation});
    if (r.objective_done) {
      out.subtask_done = true;
      break;
    }
  }
  return out;
}

}  // namespace pnp::rl

namespace pnp::rl {

SubtaskEpisode run_end_to_end_episode(sim::Environment& env, sim::SubtaskPolicy& policy,
                                      const ExplorationNoise& noise, std::uint64_t episode_seed,
                                      Rng& noise_rng) {
  SubtaskEpisode out;
  env.reset(episode_seed);
  while (!env.needs_reset()) {
    const sim::Observation observation = env.observation();
    const sim::Goal goal = env.episode_goal();
    // The subtask argument only matters to a scripted gripper, which end-to-end never has.
    const sim::Action action = explore(
        policy.act(sim::Subtask::kRetract, observation, goal, env.task_state()), noise, noise_rng);
    const sim::StepResult r = env.step(action, goal, sim::Objective::kTask);
    ++out.env_steps;
    if (r.fault != sim::PhysicsFault::kNone) break;
    out.segment.push_back({observation, action, goal, r.observation});
  }
  out.subtask_done = !out.segment.empty() && env.needs_reset() &&
                     sim::is_task_success(env.task_state().object, env.episode_goal());
  return out;
}

}  // namespace pnp::rl
