#pragma once
// The learning curve and the stopping rule shared by every trainer: evaluate at a fixed
// interval of training environment steps; stop when two consecutive evaluations reach
// the target (steps_to_target = the training steps at the first of them) or at the cap.

#include <functional>
#include <string>
#include <vector>

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
  std::string detail;             // choreographer: the most frequent greedy sequence
  double critic_loss = 0;         // mean over the last interval's updates
  double actor_loss = 0;
  long long updates = 0;
};

struct StopRule {
  long long max_steps = 200'000;
  double target_success = 0.95;
  long long eval_interval_steps = 1000;
  int eval_episodes = 100;
  int consecutive = 2;
  void validate() const;
};

struct TrainingResult;
// Training wall time (evaluation excluded) until the first of the two evaluations that
// reached the target, or until the run stopped if it never did.
double wall_to_target(const TrainingResult& result);

struct TrainingResult {
  bool reached = false;
  long long steps_to_target = -1;  // -1: not reached
  double final_success = 0;        // last evaluation
  long long train_env_steps = 0;
  long long train_episodes = 0;
  long long eval_env_steps = 0;  // spent on evaluation: not counted in training
  double wall_s = 0;             // everything
  double eval_wall_s = 0;        // of which evaluation
  std::vector<CurvePoint> curve;
};

// Tracks consecutive successes; returns true when training should stop.
class StopTracker {
 public:
  explicit StopTracker(const StopRule& rule) : rule_(rule) {}
  // `score` is what must reach the target (task success, or for a subtask expert the
  // lower of task and subtask success).
  bool record(const CurvePoint& point, double score, TrainingResult& result);

 private:
  StopRule rule_;
  int streak_ = 0;
  long long streak_start_ = -1;
};

using ProgressCallback = std::function<void(const CurvePoint&)>;

}  // namespace pnp::rl
