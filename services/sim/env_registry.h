#pragma once
// The simulation service's state: batches of environments by id, each used by one call
// at a time, closed on request or after their idle timeout. Plain C++ (no gRPC), so it
// is tested on its own. Ids are "env-<n>" from a counter: nothing here is random, so a
// batch belongs to the principal that created it and is invisible to every other (under
// an auth policy; without one, callers are not told apart).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "sim/actuation.h"
#include "sim/environment.h"
#include "sim/world_cache.h"
#include "sim/world_model.h"

namespace pnp::services {

struct EnvBatch {
  std::shared_ptr<const sim::WorldModel> world;
  std::uint64_t seed = 0;
  sim::Actuation actuation = sim::Actuation::kMocap;
  std::vector<std::unique_ptr<sim::Environment>> envs;
  std::vector<std::uint64_t> episodes;  // episodes started, per environment
  std::string owner;                    // the creating principal; empty: no auth policy
  std::chrono::steady_clock::duration idle_timeout{};
  // Set by each call that uses the batch (under `mutex`) and read by the expiry sweep
  // (under the registry's lock): atomic, since the two hold different locks.
  std::atomic<std::chrono::steady_clock::time_point> last_used{};
  std::mutex mutex;  // one call at a time per batch

  // Starts the next episode of environment k: seeded from (seed, k, episode number).
  void reset(std::size_t k);
  // Starts an episode of environment k from an explicit seed (a trainer's own stream).
  void reset(std::size_t k, std::uint64_t episode_seed);
  // Marks the batch used now (what the idle timeout counts from).
  void touch() { last_used.store(std::chrono::steady_clock::now(), std::memory_order_relaxed); }
};

class EnvRegistry {
 public:
  static constexpr int kMaxBatch = 64;
  static constexpr int kMaxEnvironments = 256;  // over all batches
  // What one principal may hold: half, so that one agent cannot take them all.
  static constexpr int kMaxEnvironmentsPerPrincipal = kMaxEnvironments / 2;
  static constexpr std::chrono::seconds kMaxIdleTimeout{3600};

  // Validated: count in [1, 64], idle timeout in (0, 3600 s], an actuation the robot has;
  // RESOURCE_EXHAUSTED past 256 environments in all, or 128 held by `owner` (the calling
  // principal; empty without an auth policy: not counted apart).
  std::string create(sim::Robot robot, sim::ObjectShape object, sim::WorldProfile world,
                     sim::Actuation actuation, std::uint64_t seed, int count,
                     std::chrono::steady_clock::duration idle_timeout,
                     const std::string& owner = "");
  // NOT_FOUND for an unknown or expired id, or a batch `owner` did not create (as if it
  // did not exist); marks the batch used.
  std::shared_ptr<EnvBatch> get(const std::string& id, const std::string& owner = "");
  void close(const std::string& id, const std::string& owner = "");  // NOT_FOUND as get
  // Closes batches idle past their timeout; returns how many.
  int expire(std::chrono::steady_clock::time_point now);
  int environments() const;

 private:
  void release(const std::string& owner, int count);  // under mutex_

  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<EnvBatch>> batches_;
  std::map<std::string, int> held_;  // environments per owner (non-empty owners)
  std::uint64_t next_id_ = 1;
  int environments_ = 0;
  sim::WorldCache worlds_;  // one compiled world per robot, object and profile
};

}  // namespace pnp::services
