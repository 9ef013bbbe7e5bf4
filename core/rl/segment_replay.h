#pragma once
// Replay of real subtask segments. A segment is one run of one objective: its own
// boundaries, its own done flags (the objective's termination predicate), and the goal
// the expert acted on stored with each transition (never another). Hindsight goals
// ("future" strategy) come only from later steps of the same segment, and a relabelled
// transition's reward and done flag are recomputed for its new goal by the same
// functions the environment uses. Capacity is in transitions; the oldest are
// overwritten first, which keeps every stored transition's future steps stored too.

#include <cstdint>
#include <vector>

#include "common/rng.h"
#include "sim/observation.h"
#include "sim/subtask.h"

namespace pnp::rl {

struct Transition {
  sim::Observation observation;
  sim::Action action;
  sim::Goal goal;  // the goal acted on
  sim::Observation next_observation;
};

struct SampledBatch {
  // Column-per-sample, float for the networks; sized by sample().
  std::vector<float> observation, next_observation;  // 25 x B
  std::vector<float> goal;                           // 3 x B (possibly relabelled)
  std::vector<float> action;                         // 4 x B
  std::vector<float> reward, done;                   // B
  int relabelled = 0;
};

enum class RewardKind {
  kDense,   // -||achieved - goal|| (the subtask experts)
  kSparse,  // -1 until the achieved goal is within 0.05 m of the goal, then 0 (end-to-end)
};

class SegmentReplay {
 public:
  SegmentReplay(long long capacity, sim::Objective objective, double object_width_m,
                RewardKind reward = RewardKind::kDense);

  // Adds one segment (in time order). Segments longer than the capacity are refused.
  void add_segment(const std::vector<Transition>& segment);

  std::size_t size() const { return size_; }
  long long segments_added() const { return segments_; }
  sim::Objective objective() const { return objective_; }

  // Samples `batch` transitions uniformly; each is relabelled with probability
  // future_probability to the achieved goal of a uniformly chosen step at or after it
  // in its segment.
  void sample(int batch, double future_probability, Rng& rng, SampledBatch& out) const;

  // For tests: the done flag and reward a stored transition gets under `goal`.
  float done_for(std::size_t index, const sim::Goal& goal) const;
  float reward_for(std::size_t index, const sim::Goal& goal) const;
  std::size_t steps_to_segment_end(std::size_t index) const { return to_end_[index]; }
  sim::Goal next_achieved(std::size_t index) const;

 private:
  sim::TaskState next_state(std::size_t index, const sim::Goal& goal) const;

  std::size_t capacity_;
  sim::Objective objective_;
  double object_width_m_;
  RewardKind reward_kind_;
  std::vector<float> observation_, next_observation_, goal_, action_, next_achieved_;
  std::vector<std::uint32_t> to_end_;  // transitions left in the segment, this one included
  std::size_t next_ = 0, size_ = 0;
  long long segments_ = 0;
};

// The probability of relabelling for HER's "future" strategy with ratio k.
inline double future_probability(int her_k) {
  return 1.0 - 1.0 / (1.0 + her_k);
}

}  // namespace pnp::rl
