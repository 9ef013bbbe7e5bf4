#include "rl/hlc_episode.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.h"
#include "sim/scripted_expert.h"

namespace pnp::rl {

std::array<double, sim::kNumSubtasks> masked_softmax(
    const std::array<double, sim::kNumSubtasks>& logits,
    const std::array<bool, sim::kNumSubtasks>& available) {
  double top = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < logits.size(); ++k)
    if (available[k]) top = std::max(top, logits[k]);
  std::array<double, sim::kNumSubtasks> p{};
  double sum = 0;
  for (std::size_t k = 0; k < p.size(); ++k)
    if (available[k]) sum += p[k] = std::exp(logits[k] - top);
  for (double& v : p) v /= sum;
  return p;
}

int choose_subtask(const std::array<double, sim::kNumSubtasks>& p, bool sample, Rng& rng) {
  if (!sample) return static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin());
  double u = rng.uniform();
  for (std::size_t k = 0; k < p.size(); ++k) {
    if ((u -= p[k]) < 0) return static_cast<int>(k);
  }
  // The probabilities sum to 1 only up to rounding, so u can outlast them: the last one
  // that can be chosen, never a masked-out subtask.
  for (std::size_t k = p.size(); k-- > 0;)
    if (p[k] > 0) return static_cast<int>(k);
  throw_internal("choose_subtask: no subtask has a positive probability");
}

int choose_uniformly(const std::array<bool, sim::kNumSubtasks>& available, Rng& rng) {
  const auto count = std::count(available.begin(), available.end(), true);
  if (count == 0) throw_internal("choose_uniformly: no subtask is available");
  auto pick = std::min(static_cast<long>(rng.uniform() * static_cast<double>(count)), count - 1);
  for (std::size_t k = 0; k < available.size(); ++k)
    if (available[k] && pick-- == 0) return static_cast<int>(k);
  throw_internal("choose_uniformly: unreachable");
}

std::array<bool, sim::kNumSubtasks> available_subtasks(const sim::TaskState& state,
                                                       bool mask_finished) {
  std::array<bool, sim::kNumSubtasks> out{};
  if (!mask_finished) {
    out.fill(true);
    return out;
  }
  bool any = false;
  for (sim::Subtask s : sim::kAllSubtasks) {
    const auto k = static_cast<std::size_t>(s);
    out[k] = !sim::objective_done(sim::objective_of(s), state);
    any = any || out[k];
  }
  if (!any) out.fill(true);  // cannot happen before the object is placed; never choose nothing
  return out;
}

std::array<double, sim::kNumSubtasks> decision_probabilities(
    std::array<double, sim::kNumSubtasks> logits, const sim::TaskState& state,
    const ChoreographerSpec& spec) {
  const auto available = available_subtasks(state, spec.mask_finished);
  if (spec.chain_prior != 0) {
    // The subtask after the furthest one whose predicate holds: approach before anything,
    // manipulate once reached, retract once grasped (when the grasp lifts the hand off
    // approach's point, approach is unfinished again, yet manipulate's work stands).
    std::size_t next = 0;
    for (std::size_t k = sim::kNumSubtasks; k-- > 0;) {
      if (sim::objective_done(sim::objective_of(sim::kAllSubtasks[k]), state)) {
        next = k + 1;
        break;
      }
    }
    if (next < sim::kNumSubtasks) logits[next] += spec.chain_prior;
  }
  return masked_softmax(logits, available);
}

HlcEpisode run_hlc_episode(sim::Environment& env, ChoreographerNet& net,
                           const std::array<sim::SubtaskPolicy*, sim::kNumSubtasks>& experts,
                           std::uint64_t episode_seed, bool sample, Rng& choice_rng,
                           bool explore_first) {
  HlcEpisode out;
  env.reset(episode_seed);
  out.goal = env.episode_goal();
  net.reset_state();
  nn::Matrix input;
  sim::StepResult last;
  while (!env.needs_reset()) {
    HlcDecision d;
    out.observations.push_back(env.observation());
    net.encode(env.observation(), env.episode_goal(), env.task_state(), input);
    std::array<double, sim::kNumSubtasks> logits{};
    out.caches.emplace_back();
    net.step(input, out.caches.back(), logits, d.value);
    d.probabilities = decision_probabilities(logits, env.task_state(), net.spec());
    d.exploring = explore_first && out.decisions.empty();
    d.choice = d.exploring
                   ? choose_uniformly(
                         available_subtasks(env.task_state(), net.spec().mask_finished), choice_rng)
                   : choose_subtask(d.probabilities, sample, choice_rng);
    const auto subtask = sim::kAllSubtasks[static_cast<std::size_t>(d.choice)];
    const sim::Objective objective = sim::objective_of(subtask);
    for (int t = 0; t < sim::step_cap(subtask, env.episode_steps()) && !env.needs_reset(); ++t) {
      const sim::TaskState state = env.task_state();
      const sim::Goal goal = sim::objective_goal(objective, state);
      const sim::Action a =
          experts[static_cast<std::size_t>(d.choice)]->act(subtask, env.observation(), goal, state);
      last = env.step(a, goal, objective);
      ++d.steps;
      ++out.env_steps;
      if (last.objective_done || last.fault != sim::PhysicsFault::kNone) break;
    }
    out.decisions.push_back(d);
    if (last.fault != sim::PhysicsFault::kNone) break;
    // Once retract has placed the object, the arm idles with the gripper closed until
    // the episode's last step (the paper's protocol): further decisions could only hold or undo it,
    // and ~30 one-step "hold" decisions buried the three that matter.
    if (subtask == sim::Subtask::kRetract && last.objective_done) {
      while (!env.needs_reset()) {
        last = env.step(sim::idle_action(), env.episode_goal(), sim::Objective::kTask);
        ++out.env_steps;
        if (last.fault != sim::PhysicsFault::kNone) break;
      }
    }
  }
  out.success = last.fault == sim::PhysicsFault::kNone && last.task_success;
  if (!out.decisions.empty()) out.decisions.back().reward = out.success ? 1.0 : 0.0;
  return out;
}

}  // namespace pnp::rl
