#pragma once
// Where a training run's wall time went, by phase: what to make faster first. The trainers
// measure it (rl/wall_breakdown.h); the store keeps each run's sum over the processes that
// trained it (store/records.h).
//
// Subtask experts and the end-to-end baseline (DDPG+HER, behaviour cloning): rollouts
// (the training episodes' environment steps and policy calls, on the trainer's threads,
// and their transitions stored), updates (replay sampling and gradient steps), evaluation
// (the stop rule's episodes), reporting (the on_evaluation and progress callbacks:
// checkpoints and store writes) and other (setup, demonstrations, the rest). The
// choreographer's A3C workers run episodes and compute gradients side by side, so there
// rollouts include each worker's gradient computation, and updates are the gradients'
// application to the shared network, one episode at a time.

namespace pnp {

struct WallBreakdown {
  double rollout_s = 0;
  double update_s = 0;
  double eval_s = 0;
  double report_s = 0;
  double other_s = 0;
  double total_s = 0;  // the phases' sum

  double phases_sum() const { return rollout_s + update_s + eval_s + report_s + other_s; }

  WallBreakdown& operator+=(const WallBreakdown& more) {
    rollout_s += more.rollout_s;
    update_s += more.update_s;
    eval_s += more.eval_s;
    report_s += more.report_s;
    other_s += more.other_s;
    total_s += more.total_s;
    return *this;
  }
  bool operator==(const WallBreakdown&) const = default;
};

}  // namespace pnp
