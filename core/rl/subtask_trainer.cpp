#include "rl/subtask_trainer.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include "rl/end_to_end_evaluation.h"
#include "rl/learned_expert.h"
#include "rl/seed_streams.h"
#include "rl/subtask_rollout.h"
#include "rl/update_schedule.h"
#include "sim/scripted_evaluation.h"
#include "sim/scripted_expert.h"

namespace pnp::rl {
namespace {

// The gripper script of an expert that does not learn its gripper; nullopt when it does.
std::optional<sim::GripperScript> scripted_gripper(const DdpgHerConfig& ddpg) {
  if (ddpg.learn_gripper) return std::nullopt;
  return ddpg.gripper_script;
}

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Observations and goals of a new segment, for the normalisers: the goals acted on and
// the achieved goals hindsight relabelling will substitute.
void update_normalizers(DdpgHerAgent& agent, const std::vector<Transition>& segment,
                        sim::Objective objective, double object_width_m) {
  if (segment.empty()) return;
  std::vector<sim::Observation> observations;
  std::vector<sim::Goal> goals;
  for (const Transition& tr : segment) {
    observations.push_back(tr.observation);
    goals.push_back(tr.goal);
    goals.push_back(sim::achieved_goal(
        objective, sim::TaskState::from(tr.next_observation, tr.goal, object_width_m)));
  }
  agent.update_normalizers(observations, goals);
}

// DAgger labelling: the action stored for each visited state is the scripted expert's.
void label_with_teacher(std::vector<Transition>& segment, sim::Subtask subtask,
                        double object_width_m) {
  for (Transition& tr : segment) {
    // For retract the goal acted on is the episode goal; the other experts ignore it.
    tr.action = sim::scripted_action(subtask,
                                     sim::TaskState::from(tr.observation, tr.goal, object_width_m));
  }
}

// A worker's own copies of the prefix experts (policies are not shared between threads);
// null entries become the scripted expert.
class PrefixPolicies {
 public:
  explicit PrefixPolicies(const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks>& prefix) {
    for (std::size_t k = 0; k < prefix.size(); ++k) {
      if (prefix[k]) owned_[k] = prefix[k]->clone();
      policies_[k] = prefix[k] ? owned_[k].get() : &scripted_;
    }
  }
  const sim::SubtaskPolicies& get() const { return policies_; }

 private:
  sim::ScriptedPolicy scripted_;
  std::array<std::unique_ptr<sim::SubtaskPolicy>, sim::kNumSubtasks> owned_;
  sim::SubtaskPolicies policies_{};
};

}  // namespace

double expert_stop_score(const CurvePoint& point, sim::Subtask subtask, bool end_to_end) {
  // Approach and manipulate must also do their own subtask: the scripted experts after
  // them can recover from a poor one (a manipulate that never closes is rescued by the
  // retract closing the gripper), so task success alone would credit an expert that
  // only runs out its step cap. Nothing follows retract, and its predicate is a
  // stricter tolerance (0.01 m) of what task success measures (0.05 m).
  return end_to_end || subtask == sim::Subtask::kRetract
             ? point.task_success
             : std::min(point.task_success, point.subtask_success);
}

DdpgHerConfig agent_config(const SubtaskTrainingConfig& config) {
  DdpgHerConfig agent = config.ddpg;
  const bool holds =
      config.algorithm != ExpertAlgorithm::kEndToEnd && config.subtask == sim::Subtask::kRetract;
  if (!holds) agent.gripper_commitment = 0;
  return agent;
}

SubtaskTrainingOutput train_subtask_expert(const sim::EnvFactory& envs,
                                           const SubtaskTrainingConfig& config,
                                           const ProgressCallback& progress) {
  config.ddpg.validate();
  config.stop.validate();
  const auto start = Clock::now();
  const PhaseClock phase_clock;
  WallBreakdown phases;
  Rng init_rng(stream_seed(config.seed, Stream::kNetworkInit));
  const bool end_to_end = config.algorithm == ExpertAlgorithm::kEndToEnd;
  auto agent = std::make_unique<DdpgHerAgent>(agent_config(config), init_rng);
  if (config.init) restore_agent(*agent, *config.init);
  const sim::Objective objective =
      end_to_end ? sim::Objective::kTask : sim::objective_of(config.subtask);
  const double object_width = envs.object_width_m();
  SegmentReplay replay(config.ddpg.buffer_size, objective, object_width,
                       end_to_end ? RewardKind::kSparse : RewardKind::kDense);
  Rng sample_rng(stream_seed(config.seed, Stream::kReplaySampling));
  ThreadPool pool(config.threads);

  const auto episodes_per_cycle = static_cast<std::size_t>(config.ddpg.episodes_per_cycle);
  std::vector<std::unique_ptr<sim::Environment>> rollout_envs;
  for (std::size_t i = 0; i < episodes_per_cycle; ++i) rollout_envs.push_back(envs.make());
  const ExplorationNoise noise{config.ddpg.noise_eps, config.ddpg.random_eps,
                               config.ddpg.random_gripper, config.ddpg.learn_gripper};
  const double future_p = future_probability(config.ddpg.her_k);
  const std::uint64_t episode_stream = stream_seed(config.seed, Stream::kTrainingEpisodes);
  const std::uint64_t noise_stream = stream_seed(config.seed, Stream::kExploration);
  const std::uint64_t eval_stream = stream_seed(config.seed, Stream::kEvaluation);

  TrainingResult result;
  StopTracker stop(config.stop);
  if (stop.resume(
          config.control,
          [&](const CurvePoint& p) { return expert_stop_score(p, config.subtask, end_to_end); },
          result)) {
    return {std::move(result), std::move(agent)};
  }
  const bool resumed = !config.control.resume_curve.empty() || config.control.resume_counters;
  const double wall_offset = result.wall_s;
  SampledBatch batch;
  std::vector<SubtaskEpisode> episodes(episodes_per_cycle);
  long long next_eval = config.stop.eval_interval_steps;
  while (next_eval <= result.train_env_steps) next_eval += config.stop.eval_interval_steps;
  double loss_sum_critic = 0, loss_sum_actor = 0;
  long long updates_since_eval = 0;
  UpdateSchedule schedule(config.ddpg);
  const sim::ScriptedPolicy scripted;

  // Demonstrations: scripted episodes of this subtask, counted as training episodes,
  // stored in the replay, cloned into the actor before exploration starts, and kept as a
  // behaviour-cloning term in every actor update.
  const bool ddpg = config.algorithm == ExpertAlgorithm::kDdpgHer || end_to_end;
  SegmentReplay demo_replay(config.ddpg.buffer_size, objective, object_width);
  SampledBatch demo_batch;
  if (ddpg && !end_to_end && config.ddpg.demo_episodes > 0 && !config.init && !resumed) {
    const auto demos = static_cast<std::size_t>(config.ddpg.demo_episodes);
    std::vector<SubtaskEpisode> demo(demos);
    pool.parallel_for(demos, [&](std::size_t i) {
      const auto env = envs.make();
      sim::ScriptedPolicy teacher;
      const PrefixPolicies prefix(config.prefix);
      Rng unused(0);
      demo[i] = run_subtask_episode(*env, config.subtask, prefix.get(), teacher, nullptr,
                                    derive_seed(episode_stream, i), unused);
    });
    for (const SubtaskEpisode& e : demo) {
      replay.add_segment(e.segment);
      demo_replay.add_segment(e.segment);
      update_normalizers(*agent, e.segment, objective, object_width);
      result.train_env_steps += e.env_steps;
      ++result.train_episodes;
    }
    for (int u = 0; u < config.ddpg.demo_pretrain_updates && demo_replay.size() > 0; ++u) {
      demo_replay.sample(config.ddpg.batch_size, 0.0, sample_rng, batch);
      agent->behaviour_clone(batch);
    }
    agent->sync_targets();
  }

  for (;;) {
    if (config.control.stop.stop_requested()) {
      result.cancelled = true;
      break;
    }
    // Rollouts: one episode per environment, in parallel; each episode's environment
    // and noise seeds depend only on its index, so any thread count gives the same data.
    const auto rollout_start = Clock::now();
    const LearnedExpert learner(agent->snapshot(), scripted_gripper(config.ddpg));
    const long long first_episode = result.train_episodes;
    const bool offline = config.algorithm == ExpertAlgorithm::kBcOffline;
    pool.parallel_for(episodes_per_cycle, [&](std::size_t i) {
      sim::ScriptedPolicy teacher;
      const PrefixPolicies prefix(config.prefix);
      const auto own = learner.clone();
      sim::SubtaskPolicy& actor = offline ? static_cast<sim::SubtaskPolicy&>(teacher) : *own;
      const auto index = static_cast<std::uint64_t>(first_episode) + i;
      Rng noise_rng(derive_seed(noise_stream, index));
      if (end_to_end) {
        episodes[i] = run_end_to_end_episode(*rollout_envs[i], actor, noise,
                                             derive_seed(episode_stream, index), noise_rng);
        return;
      }
      episodes[i] = run_subtask_episode(*rollout_envs[i], config.subtask, prefix.get(), actor,
                                        offline ? nullptr : &noise,
                                        derive_seed(episode_stream, index), noise_rng);
      if (config.algorithm == ExpertAlgorithm::kBcOnline) {
        label_with_teacher(episodes[i].segment, config.subtask, object_width);
      }
    });
    std::size_t stored = 0;
    for (const SubtaskEpisode& e : episodes) {
      replay.add_segment(e.segment);
      update_normalizers(*agent, e.segment, objective, object_width);
      result.train_env_steps += e.env_steps;
      ++result.train_episodes;
      stored += e.segment.size();
    }
    PhaseClock::add(phases.rollout_s, rollout_start);
    // Updates.
    const auto update_start = Clock::now();
    const int cycle_updates = schedule.updates_for(stored);
    if (replay.size() > 0) {
      for (int u = 0; u < cycle_updates; ++u) {
        if (!ddpg) {  // behaviour cloning: regress the actor on the labelled actions
          replay.sample(config.ddpg.batch_size, 0.0, sample_rng, batch);
          loss_sum_actor += agent->behaviour_clone(batch);
          ++result.updates;
          ++updates_since_eval;
          continue;
        }
        replay.sample(config.ddpg.batch_size, future_p, sample_rng, batch);
        const bool with_demos = demo_replay.size() > 0 && config.ddpg.demo_bc_weight > 0;
        if (with_demos)
          demo_replay.sample(config.ddpg.demo_batch_size, 0.0, sample_rng, demo_batch);
        const UpdateStats s = agent->update(batch, with_demos ? &demo_batch : nullptr);
        loss_sum_critic += s.critic_loss;
        loss_sum_actor += s.actor_loss;
        ++result.updates;
        ++updates_since_eval;
      }
      if (ddpg) agent->update_targets(cycle_updates);
    }
    PhaseClock::add(phases.update_s, update_start);
    if (config.control.on_steps) config.control.on_steps(result.train_env_steps);
    if (result.train_env_steps < next_eval) continue;

    // Evaluation on fresh, seeded episodes training never sees.
    const auto eval_start = Clock::now();
    const std::uint64_t eval_seed =
        evaluation_round_seed(eval_stream, config.stop.fresh_eval_scenes, result.curve.size());
    const LearnedExpert learned(agent->snapshot(), scripted_gripper(config.ddpg));
    CurvePoint point;
    if (end_to_end) {
      const EndToEndReport report =
          evaluate_end_to_end(envs, learned, config.stop.eval_episodes, eval_seed, pool);
      result.eval_env_steps += report.env_steps;
      point.task_success = point.subtask_success = report.success_rate;
    } else {
      std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks> experts{&scripted, &scripted,
                                                                       &scripted};
      for (sim::Subtask other : sim::kAllSubtasks) {
        const auto k = static_cast<std::size_t>(other);
        const auto& around = other < config.subtask ? config.prefix : config.successors;
        if (other != config.subtask && around[k]) experts[k] = around[k];
      }
      experts[static_cast<std::size_t>(config.subtask)] = &learned;
      const auto report =
          sim::evaluate_pipeline(envs, experts, config.stop.eval_episodes, eval_seed, pool);
      result.eval_env_steps += report.env_steps;
      point.task_success = report.success_rate;
      point.subtask_success = report.subtask_success_rate[static_cast<std::size_t>(config.subtask)];
      point.subtask_mean_steps =
          report.subtask_mean_steps[static_cast<std::size_t>(config.subtask)];
    }
    result.eval_wall_s += seconds_since(eval_start);
    PhaseClock::add(phases.eval_s, eval_start);
    point.env_steps = result.train_env_steps;
    point.episodes = result.train_episodes;
    point.wall_s = wall_offset + seconds_since(start);
    point.eval_wall_s = result.eval_wall_s;
    point.critic_loss =
        updates_since_eval ? loss_sum_critic / static_cast<double>(updates_since_eval) : 0;
    point.actor_loss =
        updates_since_eval ? loss_sum_actor / static_cast<double>(updates_since_eval) : 0;
    point.updates = result.updates;
    loss_sum_critic = loss_sum_actor = 0;
    updates_since_eval = 0;
    while (next_eval <= result.train_env_steps) next_eval += config.stop.eval_interval_steps;
    point.stop_score = expert_stop_score(point, config.subtask, end_to_end);
    const bool done = stop.record(point, point.stop_score, result);
    const auto report_start = Clock::now();
    if (config.on_evaluation) config.on_evaluation(point, *agent);
    if (progress) progress(point);
    PhaseClock::add(phases.report_s, report_start);
    if (done) break;
  }
  result.wall_s = wall_offset + seconds_since(start);
  result.breakdown = phase_clock.finish(phases);
  return {std::move(result), std::move(agent)};
}

}  // namespace pnp::rl
