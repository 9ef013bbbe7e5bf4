#include "rl/segment_replay.h"

#include <algorithm>
#include <string>

#include "common/error.h"

namespace pnp::rl {
namespace {

constexpr std::size_t kObs = sim::kObservationSize;
constexpr std::size_t kGoal = sim::kGoalSize;
constexpr std::size_t kAct = sim::kActionSize;

template <typename Vec>
void store(std::vector<float>& dst, std::size_t slot, std::size_t width, const Vec& v) {
  for (std::size_t k = 0; k < width; ++k)
    dst[slot * width + k] = static_cast<float>(v(static_cast<Eigen::Index>(k)));
}

}  // namespace

SegmentReplay::SegmentReplay(long long capacity, sim::Objective objective, double object_width_m,
                             RewardKind reward)
    : capacity_(static_cast<std::size_t>(capacity)),
      objective_(objective),
      object_width_m_(object_width_m),
      reward_kind_(reward) {
  if (capacity <= 0)
    throw_invalid_argument("buffer_size", "a positive integer", std::to_string(capacity));
  // Storage grows with use (up to capacity), so a large default buffer costs nothing
  // until it fills.
}

void SegmentReplay::add_segment(const std::vector<Transition>& segment) {
  if (segment.empty()) return;
  if (segment.size() > capacity_) {
    throw_invalid_argument("segment", "at most buffer_size transitions",
                           std::to_string(segment.size()));
  }
  for (std::size_t t = 0; t < segment.size(); ++t) {
    const std::size_t slot = next_;
    if (slot >= to_end_.size()) {  // first pass through the ring: grow
      observation_.resize((slot + 1) * kObs);
      next_observation_.resize((slot + 1) * kObs);
      goal_.resize((slot + 1) * kGoal);
      action_.resize((slot + 1) * kAct);
      next_achieved_.resize((slot + 1) * kGoal);
      to_end_.resize(slot + 1);
    }
    const Transition& tr = segment[t];
    store(observation_, slot, kObs, tr.observation);
    store(next_observation_, slot, kObs, tr.next_observation);
    store(goal_, slot, kGoal, tr.goal);
    store(action_, slot, kAct, tr.action);
    const sim::TaskState next = sim::TaskState::from(tr.next_observation, tr.goal, object_width_m_);
    store(next_achieved_, slot, kGoal, sim::achieved_goal(objective_, next));
    to_end_[slot] = static_cast<std::uint32_t>(segment.size() - t);
    next_ = (next_ + 1) % capacity_;
    size_ = std::min(size_ + 1, capacity_);
  }
  ++segments_;
}

sim::Goal SegmentReplay::next_achieved(std::size_t index) const {
  return {static_cast<double>(next_achieved_[index * kGoal]),
          static_cast<double>(next_achieved_[index * kGoal + 1]),
          static_cast<double>(next_achieved_[index * kGoal + 2])};
}

sim::TaskState SegmentReplay::next_state(std::size_t index, const sim::Goal& goal) const {
  sim::Observation o;
  for (std::size_t k = 0; k < kObs; ++k)
    o(static_cast<Eigen::Index>(k)) = static_cast<double>(next_observation_[index * kObs + k]);
  // The episode goal only matters to the retract/task objectives, whose goal this is.
  return sim::TaskState::from(o, goal, object_width_m_);
}

float SegmentReplay::done_for(std::size_t index, const sim::Goal& goal) const {
  return sim::objective_done_for_goal(objective_, next_state(index, goal), goal) ? 1.0f : 0.0f;
}

float SegmentReplay::reward_for(std::size_t index, const sim::Goal& goal) const {
  if (reward_kind_ == RewardKind::kSparse) {
    return sim::is_task_success(next_achieved(index), goal) ? 0.0f : -1.0f;
  }
  return static_cast<float>(sim::compute_reward(next_achieved(index), goal));
}

void SegmentReplay::sample(int batch, double future_prob, Rng& rng, SampledBatch& out) const {
  if (size_ == 0) throw_failed_precondition("sample: the replay buffer is empty");
  const auto b = static_cast<std::size_t>(batch);
  out.observation.resize(b * kObs);
  out.next_observation.resize(b * kObs);
  out.goal.resize(b * kGoal);
  out.action.resize(b * kAct);
  out.reward.resize(b);
  out.done.resize(b);
  out.relabelled = 0;
  for (std::size_t i = 0; i < b; ++i) {
    const std::size_t t = rng.below(size_);
    std::copy_n(observation_.begin() + static_cast<std::ptrdiff_t>(t * kObs), kObs,
                out.observation.begin() + static_cast<std::ptrdiff_t>(i * kObs));
    std::copy_n(next_observation_.begin() + static_cast<std::ptrdiff_t>(t * kObs), kObs,
                out.next_observation.begin() + static_cast<std::ptrdiff_t>(i * kObs));
    std::copy_n(action_.begin() + static_cast<std::ptrdiff_t>(t * kAct), kAct,
                out.action.begin() + static_cast<std::ptrdiff_t>(i * kAct));
    sim::Goal goal;
    if (rng.uniform() < future_prob) {
      const std::size_t future = (t + rng.below(to_end_[t])) % capacity_;  // same segment
      goal = next_achieved(future);
      ++out.relabelled;
    } else {
      goal = {static_cast<double>(goal_[t * kGoal]), static_cast<double>(goal_[t * kGoal + 1]),
              static_cast<double>(goal_[t * kGoal + 2])};
    }
    for (std::size_t k = 0; k < kGoal; ++k)
      out.goal[i * kGoal + k] = static_cast<float>(goal(static_cast<Eigen::Index>(k)));
    out.reward[i] = reward_for(t, goal);
    out.done[i] = done_for(t, goal);
  }
}

}  // namespace pnp::rl
