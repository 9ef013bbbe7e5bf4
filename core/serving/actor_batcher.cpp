#include "serving/actor_batcher.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "rl/ddpg_her_agent.h"

namespace pnp::serving {
namespace {

int checked_max_batch(int max_batch) {
  if (max_batch < 1) {
    throw_invalid_argument("max_batch", "a positive batch size", std::to_string(max_batch));
  }
  return max_batch;
}

}  // namespace

ActorBatcher::ActorBatcher(nn::Mlp actor, nn::Normalizer observation_normalizer,
                           nn::Normalizer goal_normalizer, double clip_obs, int max_batch)
    : actor_(std::move(actor)),
      observation_normalizer_(std::move(observation_normalizer)),
      goal_normalizer_(std::move(goal_normalizer)),
      clip_obs_(clip_obs),
      max_batch_(checked_max_batch(max_batch)),
      input_(sim::kObservationSize + sim::kGoalSize, max_batch_) {
  const auto n = static_cast<std::size_t>(max_batch);
  waiting_.reserve(n);
  batch_.reserve(n);
  workspaces_.resize(n);
  // One warm-up pass per size sizes every workspace now rather than under load.
  input_.setZero();
  for (int k = 1; k <= max_batch; ++k) {
    actor_.forward(input_.leftCols(k), workspaces_[static_cast<std::size_t>(k - 1)]);
  }
}

sim::Action ActorBatcher::act(const sim::Observation& observation, const sim::Goal& goal) {
  Request request{&observation, &goal};
  std::unique_lock lock(mutex_);
  waiting_.push_back(&request);
  while (!request.done) {
    if (running_) {
      batch_done_.wait(lock);
      continue;
    }
    // Lead the next batch: everyone waiting now, up to max_batch, oldest first.
    running_ = true;
    const auto take = std::min(waiting_.size(), static_cast<std::size_t>(max_batch_));
    batch_.assign(waiting_.begin(), waiting_.begin() + static_cast<std::ptrdiff_t>(take));
    waiting_.erase(waiting_.begin(), waiting_.begin() + static_cast<std::ptrdiff_t>(take));
    lock.unlock();
    run_batch(batch_);
    lock.lock();
    for (Request* r : batch_) r->done = true;
    ++stats_.batches;
    stats_.requests += batch_.size();
    stats_.largest_batch = std::max(stats_.largest_batch, static_cast<int>(batch_.size()));
    running_ = false;
    batch_done_.notify_all();
  }
  return request.action;
}

void ActorBatcher::run_batch(const std::vector<Request*>& batch) {
  const auto n = static_cast<Eigen::Index>(batch.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    const Request& r = *batch[static_cast<std::size_t>(k)];
    rl::normalise_policy_input(observation_normalizer_, goal_normalizer_, clip_obs_, *r.observation,
                               *r.goal, input_, k);
  }
  const nn::Matrix& out =
      actor_.forward(input_.leftCols(n), workspaces_[static_cast<std::size_t>(n - 1)]);
  for (Eigen::Index k = 0; k < n; ++k) {
    batch[static_cast<std::size_t>(k)]->action = out.col(k).cast<double>();
  }
}

std::size_t ActorBatcher::waiting() const {
  std::lock_guard lock(mutex_);
  return waiting_.size();
}

ActorBatcher::Pause::Pause(ActorBatcher& batcher) : batcher_(batcher) {
  std::unique_lock lock(batcher_.mutex_);
  batcher_.batch_done_.wait(lock, [&] { return !batcher_.running_; });
  batcher_.running_ = true;
}

ActorBatcher::Pause::~Pause() {
  std::lock_guard lock(batcher_.mutex_);
  batcher_.running_ = false;
  batcher_.batch_done_.notify_all();
}

BatchStats ActorBatcher::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace pnp::serving
