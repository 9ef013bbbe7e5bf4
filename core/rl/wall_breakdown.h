#pragma once
// Where a training run's wall time went, by phase: what to make faster first. Seconds of
// wall time in this process's part of the run (a resumed run starts it again at zero).
//
// Subtask experts and the end-to-end baseline (DDPG+HER, behaviour cloning): rollouts
// (the training episodes' environment steps and policy calls, on the trainer's threads,
// and their transitions stored), updates (replay sampling and gradient steps), evaluation
// (the stop rule's episodes), reporting (the on_evaluation and progress callbacks:
// checkpoints and store writes) and other (setup, demonstrations, the rest). The
// choreographer's A3C workers run episodes and compute gradients side by side, so there
// rollouts include each worker's gradient computation, and updates are the gradients'
// application to the shared network, one episode at a time.

#include <chrono>

namespace pnp::rl {

struct WallBreakdown {
  double rollout_s = 0;
  double update_s = 0;
  double eval_s = 0;
  double report_s = 0;
  double other_s = 0;
  double total_s = 0;  // this process's part of the run: the phases' sum
};

// Accumulates one phase's wall time: add(phase, since) after each stretch of it.
class PhaseClock {
 public:
  using Clock = std::chrono::steady_clock;
  PhaseClock() : start_(Clock::now()) {}
  static void add(double& phase, Clock::time_point since) {
    phase += std::chrono::duration<double>(Clock::now() - since).count();
  }
  // The breakdown with `other` the time no phase accounted for (never negative).
  WallBreakdown finish(WallBreakdown phases) const;

 private:
  Clock::time_point start_;
};

}  // namespace pnp::rl
