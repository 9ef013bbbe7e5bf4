#pragma once
// Trains the choreographer with asynchronous advantage actor-critic: W workers, each on
// its own environment and private copy of the network, run episodes concurrently and
// apply their gradients (policy gradient with GAE advantages, entropy bonus, value loss,
// global-norm clipping) to the shared parameters through one shared Adam. Gradients are
// applied in a fixed ticket order (worker w's k-th gradient is ticket k W + w) and each
// worker then copies the shared parameters, so a run is reproducible for a given seed
// and worker count however the threads are scheduled.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/thread_pool.h"
#include "nn/adam.h"
#include "rl/choreographer_net.h"
#include "rl/hlc_episode.h"
#include "rl/training_progress.h"
#include "sim/env_factory.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

struct A3cConfig {
  ChoreographerSpec network;
  int workers = 2;
  double learning_rate = 3e-3;
  // Discount per environment step: a decision whose expert ran k steps is discounted
  // gamma^k (semi-Markov; see rl/gae.h).
  double gamma = 0.97;
  double gae_lambda = 0.95;
  double entropy_weight = 0.01;
  // Exploring starts: this fraction of training episodes opens with a subtask drawn
  // uniformly from the available ones. That first decision is not the policy's, so it
  // trains neither the policy nor the value; every later one does. Without it a
  // choreographer that settles early on manipulate-retract never learns what to do after
  // approach, and so never finds that approach first is the better plan.
  double exploring_starts = 0.0;
  double value_weight = 0.5;
  double max_grad_norm = 40.0;
  void validate() const;
};

struct HlcTrainingConfig {
  std::uint64_t seed = 0;
  A3cConfig a3c;
  StopRule stop;
  std::size_t eval_threads = 0;
  // Start from these parameters (fine-tuning, or resuming with control.resume_curve)
  // instead of a fresh initialisation; the network shape must match a3c.network.
  const ChoreographerNet* init = nullptr;
  TrainingControl control;
  // Called after every evaluation with the shared network as evaluated (to checkpoint it),
  // before the progress callback; no gradient is applied while it runs.
  std::function<void(const CurvePoint&, ChoreographerNet&)> on_evaluation;
};

struct HlcTrainingOutput {
  TrainingResult result;
  std::unique_ptr<ChoreographerNet> net;
};

// Accumulates into net's gradients the policy-gradient (GAE advantages), entropy and
// value-loss terms of one sampled episode; an exploring start's first decision adds none.
void episode_gradients(ChoreographerNet& net, HlcEpisode& episode, const A3cConfig& c);

// experts: prototypes, cloned for every worker and evaluation thread.
HlcTrainingOutput train_choreographer(
    const sim::EnvFactory& envs,
    const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks>& experts,
    const HlcTrainingConfig& config, const ProgressCallback& progress = {});

struct ChoreographerEvaluation {
  double success_rate = 0;
  long long env_steps = 0;
  // The subtask sequences chosen (e.g. "AMR": approach, manipulate, retract), most
  // frequent first, with their episode counts and successes: what the choreographer does.
  struct Sequence {
    std::string choices;
    int episodes = 0;
    int successes = 0;
  };
  std::vector<Sequence> sequences;
};

// Greedy evaluation of the choreographer over the experts on episodes seeded
// derive_seed(seed, i).
ChoreographerEvaluation evaluate_choreographer(
    const sim::EnvFactory& envs, const ChoreographerNet& net,
    const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks>& experts, int episodes,
    std::uint64_t seed, ThreadPool& pool);

// "AMR" for the choices approach, manipulate, retract.
std::string choice_string(const HlcEpisode& episode);

}  // namespace pnp::rl
