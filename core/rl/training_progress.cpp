#include "rl/training_progress.h"

#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp::rl {

void StopRule::validate() const {
  if (max_steps <= 0)
    throw_invalid_argument("max_steps", "a positive integer", std::to_string(max_steps));
  if (!(target_success > 0 && target_success <= 1)) {
    throw_invalid_argument("target_success", "a value in (0, 1]", std::to_string(target_success));
  }
  if (eval_interval_steps <= 0) {
    throw_invalid_argument("eval_interval_steps", "a positive integer",
                           std::to_string(eval_interval_steps));
  }
  if (eval_episodes <= 0)
    throw_invalid_argument("eval_episodes", "a positive integer", std::to_string(eval_episodes));
  if (consecutive <= 0)
    throw_invalid_argument("consecutive", "a positive integer", std::to_string(consecutive));
}

bool StopTracker::record(const CurvePoint& point, double score, TrainingResult& result) {
  result.curve.push_back(point);
  result.curve.back().stop_score = score;
  result.final_success = point.task_success;
  result.final_score = score;
  streak_ = score >= rule_.target_success ? streak_ + 1 : 0;
  if (streak_ >= rule_.consecutive) {
    result.reached = true;
    result.steps_to_target = point.env_steps;  // the model that goes on
    return true;
  }
  return point.env_steps >= rule_.max_steps;
}

bool StopTracker::resume(const TrainingControl& control,
                         const std::function<double(const CurvePoint&)>& score,
                         TrainingResult& result) {
  const auto& curve = control.resume_curve;
  bool done = false;
  for (const CurvePoint& point : curve) done = record(point, score(point), result);
  TrainingCounters at;
  if (!curve.empty()) at = counters_of(curve.back());
  if (control.resume_counters) {
    if (control.resume_counters->env_steps < at.env_steps ||
        control.resume_counters->episodes < at.episodes) {
      throw_invalid_argument(
          "resume_counters",
          "at or after the curve's last point (" + std::to_string(at.env_steps) + " steps)",
          std::to_string(control.resume_counters->env_steps) + " steps");
    }
    at = *control.resume_counters;
  }
  result.train_env_steps = at.env_steps;
  result.train_episodes = at.episodes;
  result.updates = at.updates;
  result.wall_s = at.wall_s;
  result.eval_wall_s = at.eval_wall_s;
  return done;
}

TrainingCounters counters_of(const CurvePoint& point) {
  return {point.env_steps, point.episodes, point.updates, point.wall_s, point.eval_wall_s};
}

double wall_to_target(const TrainingResult& result) {
  for (const CurvePoint& p : result.curve) {
    if (result.reached && p.env_steps == result.steps_to_target) return p.wall_s - p.eval_wall_s;
  }
  return result.wall_s - result.eval_wall_s;
}

}  // namespace pnp::rl
