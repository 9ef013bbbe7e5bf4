#include "services/sim/env_registry.h"

#include "arm_sim/arm_env_factory.h"
#include "common/error.h"
#include "common/rng.h"

namespace pnp::services {

void EnvBatch::reset(std::size_t k) {
  reset(k, derive_seed(derive_seed(seed, k), episodes[k]));
}

void EnvBatch::reset(std::size_t k, std::uint64_t episode_seed) {
  envs[k]->reset(episode_seed);
  ++episodes[k];
}

std::string EnvRegistry::create(sim::Robot robot, sim::ObjectShape object, sim::WorldProfile world,
                                sim::Actuation actuation, std::uint64_t seed, int count,
                                std::chrono::steady_clock::duration idle_timeout,
                                const std::string& owner) {
  sim::require_supported(robot, actuation);
  if (count < 1 || count > kMaxBatch) {
    throw_invalid_argument("count", "1 to " + std::to_string(kMaxBatch), std::to_string(count));
  }
  if (idle_timeout <= std::chrono::steady_clock::duration::zero() ||
      idle_timeout > kMaxIdleTimeout) {
    throw_invalid_argument(
        "idle_timeout", "more than 0 s and at most 3600 s",
        std::to_string(std::chrono::duration<double>(idle_timeout).count()) + " s");
  }
  {
    std::lock_guard lock(mutex_);
    if (environments_ + count > kMaxEnvironments) {
      throw Error(ErrorCode::kResourceExhausted,
                  "count: " + std::to_string(count) + " more environments would exceed the " +
                      std::to_string(kMaxEnvironments) + " this server holds (" +
                      std::to_string(environments_) + " open): close some first");
    }
    if (!owner.empty() && held_[owner] + count > kMaxEnvironmentsPerPrincipal) {
      throw Error(ErrorCode::kResourceExhausted,
                  "count: " + std::to_string(count) + " more environments would exceed the " +
                      std::to_string(kMaxEnvironmentsPerPrincipal) + " one principal may hold (\"" +
                      owner + "\" holds " + std::to_string(held_[owner]) + "): close some first");
    }
    environments_ += count;  // reserved before the (slow) model loading
    if (!owner.empty()) held_[owner] += count;
  }
  auto batch = std::make_shared<EnvBatch>();
  try {
    batch->world = worlds_.get(robot, object, world);
    batch->actuation = actuation;
    batch->seed = seed;
    const auto factory = arm_sim::make_env_factory(batch->world, actuation);
    for (int k = 0; k < count; ++k) batch->envs.push_back(factory->make());
    batch->episodes.assign(static_cast<std::size_t>(count), 0);
  } catch (...) {
    std::lock_guard lock(mutex_);
    release(owner, count);
    throw;
  }
  batch->owner = owner;
  batch->idle_timeout = idle_timeout;
  batch->touch();
  std::lock_guard lock(mutex_);
  const std::string id = "env-" + std::to_string(next_id_++);
  batches_.emplace(id, std::move(batch));
  return id;
}

std::shared_ptr<EnvBatch> EnvRegistry::get(const std::string& id, const std::string& owner) {
  std::lock_guard lock(mutex_);
  const auto it = batches_.find(id);
  if (it == batches_.end() || it->second->owner != owner)
    throw Error(ErrorCode::kNotFound,
                "env_id: no environment batch \"" + id + "\" (closed or expired?)");
  it->second->touch();
  return it->second;
}

void EnvRegistry::close(const std::string& id, const std::string& owner) {
  std::lock_guard lock(mutex_);
  const auto it = batches_.find(id);
  if (it == batches_.end() || it->second->owner != owner)
    throw Error(ErrorCode::kNotFound, "env_id: no environment batch \"" + id + "\"");
  release(it->second->owner, static_cast<int>(it->second->envs.size()));
  batches_.erase(it);
}

int EnvRegistry::expire(std::chrono::steady_clock::time_point now) {
  std::lock_guard lock(mutex_);
  int closed = 0;
  for (auto it = batches_.begin(); it != batches_.end();) {
    if (now - it->second->last_used.load(std::memory_order_relaxed) > it->second->idle_timeout) {
      release(it->second->owner, static_cast<int>(it->second->envs.size()));
      it = batches_.erase(it);
      ++closed;
    } else {
      ++it;
    }
  }
  return closed;
}

void EnvRegistry::release(const std::string& owner, int count) {
  environments_ -= count;
  if (owner.empty()) return;
  const auto it = held_.find(owner);
  if (it != held_.end() && (it->second -= count) <= 0) held_.erase(it);
}

int EnvRegistry::environments() const {
  std::lock_guard lock(mutex_);
  return environments_;
}

}  // namespace pnp::services
