#include "sim/scripted_pipeline.h"

#include "sim/scripted_expert.h"

namespace pnp::sim {

EpisodeOutcome run_pipeline_episode(PickPlaceEnv& env, const SubtaskPolicies& policies,
                                    std::uint64_t seed) {
  EpisodeOutcome out;
  env.reset(seed);
  int stage = 0;  // index into kAllSubtasks; kNumSubtasks means idle
  int steps_in_stage = 0;
  StepResult last;
  while (!env.needs_reset()) {
    Action action;
    Objective objective = Objective::kTask;
    Goal goal;
    if (stage < kNumSubtasks) {
      const auto index = static_cast<std::size_t>(stage);
      const Subtask subtask = kAllSubtasks[index];
      objective = objective_of(subtask);
      const TaskState state = env.task_state();
      goal = sim::objective_goal(objective, state);
      action = policies[index]->act(subtask, env.observation(), goal, state);
    } else {
      action = idle_action();
      goal = env.episode_goal();
    }
    last = env.step(action, goal, objective);
    ++out.env_steps;
    if (last.fault != PhysicsFault::kNone) {
      out.physics_fault = true;
      break;
    }
    if (stage < kNumSubtasks) {
      const auto index = static_cast<std::size_t>(stage);
      ++out.subtask_steps[index];
      ++steps_in_stage;
      const bool capped = steps_in_stage >= step_cap(kAllSubtasks[index]);
      if (last.objective_done || capped) {
        out.subtask_done[index] = last.objective_done;
        ++stage;
        steps_in_stage = 0;
        if (stage == kNumSubtasks) out.active_steps = env.elapsed_steps();
      }
    }
  }
  if (stage < kNumSubtasks) out.active_steps = env.elapsed_steps();
  out.success = !out.physics_fault && last.task_success;
  out.final_distance_m = (env.task_state().object - env.episode_goal()).norm();
  return out;
}

EpisodeOutcome run_scripted_episode(PickPlaceEnv& env, std::uint64_t seed) {
  ScriptedPolicy scripted;
  return run_pipeline_episode(env, {&scripted, &scripted, &scripted}, seed);
}

}  // namespace pnp::sim
