#pragma once
// The learning curve and the stopping rule shared by every trainer: evaluate at a fixed
// interval of training environment steps; stop when two consecutive evaluations reach
// the target or at the cap. steps_to_target is the training steps at the last of them:
// the model that stopped the run is the one passed on (the next expert's prefix, the
// choreographer's experts, the held-out evaluation), so the steps reported are the steps
// that model consumed.

#include <functional>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "rl/wall_breakdown.h"

namespace pnp::rl {

struct CurvePoint {
  long long env_steps = 0;        // training environment steps so far (prefixes included)
  long long episodes = 0;         // training episodes so far
  double wall_s = 0;              // since the run started, evaluation included
  double eval_wall_s = 0;         // of which evaluation, cumulative
  double task_success = 0;        // object-based, on the fresh evaluation episodes
  double subtask_success = 0;     // the trained subtask's predicate fired (experts only)
  double subtask_mean_steps = 0;  // steps the trained subtask ran, mean (experts only)
  double sampled_success = 0;     // choreographer: its training episodes (sampled choices)
  // What the stop rule compares with the target: task success, or for approach and
  // manipulate the lower of task and subtask success.
  double stop_score = 0;
  std::string detail;      // choreographer: the most frequent greedy sequence
  double critic_loss = 0;  // mean over the last interval's updates
  double actor_loss = 0;
  long long updates = 0;
};

// Where a trainer's counters stand: at an evaluation (its curve point), or at the moment
// it stopped between evaluations (weights saved at a shutdown or a cancel).
struct TrainingCounters {
  long long env_steps = 0;
  long long episodes = 0;
  long long updates = 0;
  double wall_s = 0;       // since the run started, evaluation included
  double eval_wall_s = 0;  // of which evaluation
};
TrainingCounters counters_of(const CurvePoint& point);

struct StopRule {
  long long max_steps = 200'000;
  double target_success = 0.95;
  long long eval_interval_steps = 1000;
  int eval_episodes = 100;
  int consecutive = 2;
  // true: each evaluation round plays new scenes, so a deterministic policy is not judged
  // on one draw of scenes for the whole run (one unlucky draw stalled 2 of 9 runs);
  // false: every round replays the same eval_episodes scenes (smoother curves).
  bool fresh_eval_scenes = true;
  void validate() const;
};

struct TrainingResult;
// Training wall time (evaluation excluded) until the evaluation that confirmed the target
// (the model passed on), or until the run stopped if it never did.
double wall_to_target(const TrainingResult& result);

struct TrainingResult {
  bool reached = false;
  bool cancelled = false;          // stopped by TrainingControl::stop before its rule
  long long steps_to_target = -1;  // -1: not reached
  double final_success = 0;        // last evaluation: task success
  double final_score = 0;          // last evaluation: the stop rule's score
  long long train_env_steps = 0;
  long long train_episodes = 0;
  long long updates = 0;
  long long eval_env_steps = 0;  // spent on evaluation: not counted in training
  double wall_s = 0;             // everything
  double eval_wall_s = 0;        // of which evaluation
  WallBreakdown breakdown;       // this process's part of wall_s, by phase
  std::vector<CurvePoint> curve;
};

// What a caller outside the trainer controls: cancellation, and resuming a run that was
// interrupted (by a crash or a restart) from its last checkpoint.
struct TrainingControl {
  // Checked between rounds of rollouts and updates; a stopped run returns at once with
  // `cancelled` set and the result so far.
  std::stop_token stop;
  // Non-empty: the interrupted run's learning curve up to its last checkpoint (whose
  // weights the caller passes as the trainer's init). Step and episode counters continue
  // from its last point, the stop rule's streak is rebuilt from it, and new training
  // episodes continue the run's seed sequence. The replay buffer and optimiser moments
  // are not checkpointed: they refill and re-adapt (docs/LEARNING.md).
  std::vector<CurvePoint> resume_curve;
  // Set when the weights passed as init were saved after the curve's last point (the run
  // stopped between evaluations): the counters continue from these instead.
  std::optional<TrainingCounters> resume_counters;
  // After every round of rollouts and updates, with the training steps so far: a live
  // gauge between evaluations. Called from the training thread; keep it cheap.
  std::function<void(long long env_steps)> on_steps;
};

// Tracks consecutive successes; returns true when training should stop.
class StopTracker {
 public:
  explicit StopTracker(const StopRule& rule) : rule_(rule) {}
  // Replays a resumed run's curve and sets the result's counters to where it stopped
  // (control.resume_counters, else the curve's last point); `score` maps a point to what
  // must reach the target. Returns true if that curve already met the stop rule.
  // INVALID_ARGUMENT if the counters are behind the curve.
  bool resume(const TrainingControl& control, const std::function<double(const CurvePoint&)>& score,
              TrainingResult& result);
  // `score` is what must reach the target (task success, or for a subtask expert the
  // lower of task and subtask success).
  bool record(const CurvePoint& point, double score, TrainingResult& result);

 private:
  StopRule rule_;
  int streak_ = 0;
};

using ProgressCallback = std::function<void(const CurvePoint&)>;

}  // namespace pnp::rl
