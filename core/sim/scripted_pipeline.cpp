#include "sim/scripted_pipeline.h"

#include "sim/scripted_expert.h"
#include "sim/subtask_sequence.h"

namespace pnp::sim {

EpisodeOutcome run_pipeline_episode(Environment& env, const SubtaskPolicies& policies,
                                    std::uint64_t seed, const PipelineStepObserver& observer) {
  EpisodeOutcome out;
  env.reset(seed);
  SubtaskSequence sequence(env.episode_steps());
  StepResult last;
  while (!env.needs_reset()) {
    const Objective objective = sequence.objective();
    const TaskState state = env.task_state();
    const Goal goal = sim::objective_goal(objective, state);
    const Action action = sequence.idle()
                              ? idle_action()
                              : policies[static_cast<std::size_t>(sequence.current())]->act(
                                    sequence.current(), env.observation(), goal, state);
    last = env.step(action, goal, objective);
    ++out.env_steps;
    if (observer) {
      observer(env.elapsed_steps(),
               sequence.idle() ? std::nullopt : std::optional<Subtask>(sequence.current()), action,
               env.task_state());
    }
    if (last.fault != PhysicsFault::kNone) {
      out.fault = last.fault;
      break;
    }
    if (sequence.idle()) continue;
    const auto index = static_cast<std::size_t>(sequence.current());
    ++out.subtask_steps[index];
    if (sequence.record_step(last.objective_done)) {
      out.subtask_done[index] = last.objective_done;
      if (sequence.idle()) out.active_steps = env.elapsed_steps();
    }
  }
  if (!sequence.idle()) out.active_steps = env.elapsed_steps();
  out.success = !out.physics_fault() && last.task_success;
  out.final_distance_m = (env.task_state().object - env.episode_goal()).norm();
  return out;
}

EpisodeOutcome run_scripted_episode(Environment& env, std::uint64_t seed) {
  ScriptedPolicy scripted;
  return run_pipeline_episode(env, {&scripted, &scripted, &scripted}, seed);
}

}  // namespace pnp::sim
