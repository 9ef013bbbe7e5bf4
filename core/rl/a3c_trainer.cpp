#include "rl/a3c_trainer.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "common/error.h"
#include "common/thread_pool.h"
#include "nn/flat_ops.h"
#include "rl/gae.h"
#include "rl/hlc_episode.h"
#include "rl/network_limits.h"
#include "rl/seed_streams.h"

namespace pnp::rl {
namespace {

using Clock = std::chrono::steady_clock;

using Experts = std::array<std::unique_ptr<sim::SubtaskPolicy>, sim::kNumSubtasks>;

Experts clone_experts(const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks>& prototypes) {
  Experts out;
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = prototypes[k]->clone();
  return out;
}

std::array<sim::SubtaskPolicy*, sim::kNumSubtasks> raw(const Experts& e) {
  return {e[0].get(), e[1].get(), e[2].get()};
}

// Copies every parameter block (and the normaliser) of `src` into `dst`.
void copy_network(ChoreographerNet& dst, ChoreographerNet& src) {
  auto d = dst.parameter_blocks();
  auto s = src.parameter_blocks();
  for (std::size_t b = 0; b < d.size(); ++b) nn::copy_into(d[b], s[b]);
  dst.normalizer().restore(src.normalizer().sums(), src.normalizer().sums_of_squares(),
                           src.normalizer().count());
}

// Serialises gradient application in ticket order.
class TicketGate {
 public:
  void wait_for(long long ticket) {
    std::unique_lock lock(mutex_);
    turn_.wait(lock, [&] { return next_ == ticket || stopped_; });
  }
  void done() {
    {
      std::lock_guard lock(mutex_);
      ++next_;
    }
    turn_.notify_all();
  }
  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
    }
    turn_.notify_all();
  }
  bool stopped() {
    std::lock_guard lock(mutex_);
    return stopped_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable turn_;
  long long next_ = 0;
  bool stopped_ = false;
};

}  // namespace

void A3cConfig::validate() const {
  if (workers <= 0 || workers > kMaxA3cWorkers) {
    throw_invalid_argument("workers", "1 to " + std::to_string(kMaxA3cWorkers),
                           std::to_string(workers));
  }
  if (!(learning_rate > 0))
    throw_invalid_argument("learning_rate", "a positive number", std::to_string(learning_rate));
  if (!(gamma > 0 && gamma <= 1))
    throw_invalid_argument("gamma", "a value in (0, 1]", std::to_string(gamma));
  if (!(gae_lambda >= 0 && gae_lambda <= 1))
    throw_invalid_argument("gae_lambda", "a value in [0, 1]", std::to_string(gae_lambda));
  if (!(exploring_starts >= 0 && exploring_starts <= 1)) {
    throw_invalid_argument("exploring_starts", "a fraction in [0, 1]",
                           std::to_string(exploring_starts));
  }
  if (!(entropy_weight >= 0))
    throw_invalid_argument("entropy_weight", "a non-negative number",
                           std::to_string(entropy_weight));
  if (!(value_weight >= 0))
    throw_invalid_argument("value_weight", "a non-negative number", std::to_string(value_weight));
  if (!(max_grad_norm > 0))
    throw_invalid_argument("max_grad_norm", "a positive number", std::to_string(max_grad_norm));
  network.validate("network.");
}

void episode_gradients(ChoreographerNet& net, HlcEpisode& episode, const A3cConfig& c) {
  const std::size_t n = episode.decisions.size();
  std::vector<double> rewards(n), values(n), discounts(n);
  for (std::size_t t = 0; t < n; ++t) {
    rewards[t] = episode.decisions[t].reward;
    values[t] = episode.decisions[t].value;
    discounts[t] = std::pow(c.gamma, episode.decisions[t].steps);
  }
  const Advantages adv = compute_gae(rewards, values, 0.0, discounts, c.gae_lambda);
  std::vector<std::array<double, 3>> dlogits(n);
  std::vector<double> dvalue(n);
  for (std::size_t t = 0; t < n; ++t) {
    if (episode.decisions[t].exploring) {  // not the policy's choice: no loss of its own
      dlogits[t] = {};
      dvalue[t] = 0;
      continue;
    }
    const auto& p = episode.decisions[t].probabilities;
    double entropy_grad_base = 0;  // sum_k p_k log p_k
    for (double pk : p) entropy_grad_base += pk * std::log(std::max(pk, 1e-12));
    for (int k = 0; k < sim::kNumSubtasks; ++k) {
      const auto uk = static_cast<std::size_t>(k);
      const double onehot = k == episode.decisions[t].choice ? 1.0 : 0.0;
      // d(-A log p_a)/dlogit_k = -A (1[k=a] - p_k)
      const double policy = -adv.advantages[t] * (onehot - p[uk]);
      // d(-beta H)/dlogit_k = beta p_k (log p_k - sum_j p_j log p_j)
      const double entropy =
          c.entropy_weight * p[uk] * (std::log(std::max(p[uk], 1e-12)) - entropy_grad_base);
      dlogits[t][uk] = policy + entropy;
    }
    // d(0.5 w (V - R)^2)/dV
    dvalue[t] = c.value_weight * (values[t] - adv.returns[t]);
  }
  net.backward(episode.caches, dlogits, dvalue);
}

std::string choice_string(const HlcEpisode& episode) {
  static constexpr std::array<char, sim::kNumSubtasks> kLetters{'A', 'M', 'R'};
  std::string out;
  for (const HlcDecision& d : episode.decisions)
    out += kLetters[static_cast<std::size_t>(d.choice)];
  return out;
}

ChoreographerEvaluation evaluate_choreographer(
    const sim::EnvFactory& envs, const ChoreographerNet& net,
    const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks>& experts, int episodes,
    std::uint64_t seed, ThreadPool& pool) {
  const auto count = static_cast<std::size_t>(episodes);
  const std::size_t workers = std::min(pool.size(), count);
  std::vector<char> success(count, 0);
  std::vector<int> steps(count, 0);
  std::vector<std::string> choices(count);
  pool.parallel_for(workers, [&](std::size_t w) {
    const auto env = envs.make();
    ChoreographerNet own = net;
    Experts own_experts = clone_experts(experts);
    Rng unused(0);
    for (std::size_t i = w; i < count; i += workers) {
      const HlcEpisode e =
          run_hlc_episode(*env, own, raw(own_experts), derive_seed(seed, i), false, unused);
      success[i] = e.success ? 1 : 0;
      steps[i] = e.env_steps;
      choices[i] = choice_string(e);
    }
  });
  ChoreographerEvaluation out;
  std::map<std::string, ChoreographerEvaluation::Sequence> by_choices;
  for (std::size_t i = 0; i < count; ++i) {
    out.env_steps += steps[i];
    auto& sequence = by_choices[choices[i]];
    sequence.choices = choices[i];
    ++sequence.episodes;
    sequence.successes += success[i];
  }
  for (auto& [key, sequence] : by_choices) out.sequences.push_back(sequence);
  // Most frequent first; ties by the choices, so the order is reproducible.
  std::sort(out.sequences.begin(), out.sequences.end(), [](const auto& a, const auto& b) {
    return a.episodes != b.episodes ? a.episodes > b.episodes : a.choices < b.choices;
  });
  out.success_rate = static_cast<double>(std::count(success.begin(), success.end(), 1)) /
                     static_cast<double>(count);
  return out;
}

HlcTrainingOutput train_choreographer(
    const sim::EnvFactory& envs,
    const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks>& experts,
    const HlcTrainingConfig& config, const ProgressCallback& progress) {
  config.a3c.validate();
  config.stop.validate();
  const auto start = Clock::now();
  const PhaseClock phase_clock;
  WallBreakdown phases;  // written under the gate's turn
  auto shared = std::make_unique<ChoreographerNet>(config.a3c.network);
  Rng init_rng(stream_seed(config.seed, Stream::kNetworkInit));
  shared->initialise(init_rng);
  if (config.init) {
    if (!(config.init->spec() == config.a3c.network)) {
      throw_invalid_argument("init", "a choreographer of the configured network shape",
                             "another shape");
    }
    *shared = *config.init;
  }
  std::vector<nn::Adam> adams;  // one per parameter block, shared by all workers
  for (auto block : shared->parameter_blocks())
    adams.emplace_back(block.size(), nn::AdamConfig{config.a3c.learning_rate});
  ThreadPool eval_pool(config.eval_threads);
  const std::uint64_t episode_stream = stream_seed(config.seed, Stream::kTrainingEpisodes);
  const std::uint64_t choice_stream = stream_seed(config.seed, Stream::kExploration);
  const std::uint64_t eval_stream = stream_seed(config.seed, Stream::kEvaluation);

  TrainingResult result;
  StopTracker stop(config.stop);
  if (stop.resume(
          config.control, [](const CurvePoint& p) { return p.task_success; }, result)) {
    return {std::move(result), std::move(shared)};
  }
  const double wall_offset = result.wall_s;
  // Tickets continue after a resumed run's episodes, so its new episodes are new seeds.
  const long long first_ticket = result.train_episodes;
  TicketGate gate;
  long long next_eval = config.stop.eval_interval_steps;
  while (next_eval <= result.train_env_steps) next_eval += config.stop.eval_interval_steps;
  long long sampled_episodes = 0, sampled_successes = 0;  // since the last evaluation
  // Episodes other workers had in flight when training stopped: they ran, so their steps
  // count, though their gradients are never applied. Which episodes these are depends only
  // on the stopping ticket, so the total is reproducible.
  std::atomic<long long> in_flight_steps{0};
  bool cancelled = false;  // written under the gate's turn
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto workers = static_cast<long long>(config.a3c.workers);

  // Every worker's copy is taken before any thread starts, so each first episode uses
  // the initial parameters however the threads are scheduled.
  std::vector<ChoreographerNet> locals(static_cast<std::size_t>(workers), *shared);
  auto worker = [&](long long w) {
    try {
      const auto env = envs.make();
      ChoreographerNet& local = locals[static_cast<std::size_t>(w)];
      Experts own = clone_experts(experts);
      for (long long k = 0;; ++k) {
        const long long ticket = k * workers + w;
        const auto episode_index = static_cast<std::uint64_t>(first_ticket + ticket);
        Rng choice_rng(derive_seed(choice_stream, episode_index));
        // Drawn only when enabled, so runs without exploring starts keep their choices.
        const bool exploring =
            config.a3c.exploring_starts > 0 && choice_rng.uniform() < config.a3c.exploring_starts;
        HlcEpisode episode =
            run_hlc_episode(*env, local, raw(own), derive_seed(episode_stream, episode_index), true,
                            choice_rng, exploring);
        local.zero_grads();
        episode_gradients(local, episode, config.a3c);
        gate.wait_for(ticket);
        if (!gate.stopped() && config.control.stop.stop_requested()) {
          cancelled = true;
          gate.stop();
        }
        if (gate.stopped()) {
          in_flight_steps += episode.env_steps;
          return;
        }
        // Apply this worker's gradients to the shared network, in ticket order.
        const auto update_start = Clock::now();
        auto grads = local.gradient_blocks();
        double norm_sq = 0;
        for (auto g : grads) norm_sq += std::pow(nn::l2_norm(g), 2);
        const double norm = std::sqrt(norm_sq);
        const float scale = norm > config.a3c.max_grad_norm
                                ? static_cast<float>(config.a3c.max_grad_norm / norm)
                                : 1.0f;
        auto params = shared->parameter_blocks();
        for (std::size_t b = 0; b < params.size(); ++b) {
          for (float& g : grads[b]) g *= scale;
          adams[b].step(params[b], grads[b]);
        }
        for (const auto& o : episode.observations) {
          double raw_input[sim::kObservationSize + sim::kGoalSize];
          for (int i = 0; i < sim::kObservationSize; ++i) raw_input[i] = o(i);
          for (int i = 0; i < sim::kGoalSize; ++i)
            raw_input[sim::kObservationSize + i] = episode.goal(i);
          shared->normalizer().update(raw_input);
        }
        shared->normalizer().refresh();
        PhaseClock::add(phases.update_s, update_start);
        result.train_env_steps += episode.env_steps;
        ++result.train_episodes;
        ++result.updates;  // one per applied episode
        if (config.control.on_steps) config.control.on_steps(result.train_env_steps);
        ++sampled_episodes;
        sampled_successes += episode.success ? 1 : 0;
        if (result.train_env_steps >= next_eval) {
          const auto eval_start = Clock::now();
          CurvePoint point;
          const ChoreographerEvaluation evaluation = evaluate_choreographer(
              envs, *shared, experts, config.stop.eval_episodes,
              evaluation_round_seed(eval_stream, config.stop.fresh_eval_scenes,
                                    result.curve.size()),
              eval_pool);
          result.eval_env_steps += evaluation.env_steps;
          point.task_success = point.subtask_success = evaluation.success_rate;
          point.sampled_success = static_cast<double>(sampled_successes) /
                                  static_cast<double>(std::max(1LL, sampled_episodes));
          sampled_successes = sampled_episodes = 0;
          const auto& top = evaluation.sequences.front();
          point.detail = top.choices + " x" + std::to_string(top.episodes);
          result.eval_wall_s += std::chrono::duration<double>(Clock::now() - eval_start).count();
          PhaseClock::add(phases.eval_s, eval_start);
          point.env_steps = result.train_env_steps;
          point.episodes = result.train_episodes;
          point.wall_s = wall_offset + std::chrono::duration<double>(Clock::now() - start).count();
          point.updates = result.updates;
          point.eval_wall_s = result.eval_wall_s;
          while (next_eval <= result.train_env_steps) next_eval += config.stop.eval_interval_steps;
          point.stop_score = point.task_success;
          const bool finished = stop.record(point, point.stop_score, result);
          const auto report_start = Clock::now();
          if (config.on_evaluation) config.on_evaluation(point, *shared);
          if (progress) progress(point);
          PhaseClock::add(phases.report_s, report_start);
          if (finished) {
            gate.stop();
            return;
          }
        }
        copy_network(local, *shared);
        gate.done();
      }
    } catch (...) {
      std::lock_guard lock(failure_mutex);
      if (!failure) failure = std::current_exception();
      gate.stop();
    }
  };
  const auto workers_start = Clock::now();
  {
    std::vector<std::jthread> threads;
    for (long long w = 0; w < workers; ++w) threads.emplace_back(worker, w);
  }
  // What the workers did besides the serialized phases: their episodes and gradients.
  double workers_s = 0;
  PhaseClock::add(workers_s, workers_start);
  phases.rollout_s = std::max(0.0, workers_s - phases.update_s - phases.eval_s - phases.report_s);
  if (failure) std::rethrow_exception(failure);
  result.train_env_steps += in_flight_steps.load();
  result.cancelled = cancelled;
  result.wall_s = wall_offset + std::chrono::duration<double>(Clock::now() - start).count();
  result.breakdown = phase_clock.finish(phases);
  return {std::move(result), std::move(shared)};
}

}  // namespace pnp::rl
