#pragma once
// Opportunistic batching of one expert's actor across concurrent requests. A caller that
// finds the actor idle runs one forward pass for every request waiting at that moment
// (its own included) as one matrix product; requests arriving meanwhile wait and go in
// the next batch, run by whichever of them wakes first. There is no timer: a lone request
// runs at once, and batches grow only with the load. Each request's action is its own
// column of the batch, so its value does not depend on its companions beyond float
// rounding of the product (tested against the unbatched actor).

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <vector>

#include "nn/mlp.h"
#include "nn/normalizer.h"
#include "sim/observation.h"

namespace pnp::serving {

struct BatchStats {
  std::uint64_t requests = 0;
  std::uint64_t batches = 0;
  int largest_batch = 0;
};

class ActorBatcher {
 public:
  // max_batch bounds one forward pass; the workspaces for every size up to it are
  // allocated here, so serving never allocates.
  ActorBatcher(nn::Mlp actor, nn::Normalizer observation_normalizer, nn::Normalizer goal_normalizer,
               double clip_obs, int max_batch = kDefaultMaxBatch);

  static constexpr int kDefaultMaxBatch = 16;

  // The deterministic action in [-1, 1]^4. Thread-safe; blocks while a batch runs.
  sim::Action act(const sim::Observation& observation, const sim::Goal& goal);

  BatchStats stats() const;
  int max_batch() const { return max_batch_; }
  std::size_t waiting() const;  // requests queued for the next batch

  // While a Pause lives no batch starts (as if one were running): requests queue, and
  // on release they run as one batch. Lets tests build a batch of known size.
  class Pause {
   public:
    explicit Pause(ActorBatcher& batcher);
    Pause(const Pause&) = delete;
    Pause& operator=(const Pause&) = delete;
    ~Pause();

   private:
    ActorBatcher& batcher_;
  };

 private:
  struct Request {
    const sim::Observation* observation;
    const sim::Goal* goal;
    sim::Action action = sim::Action::Zero();
    bool done = false;
  };

  void run_batch(const std::vector<Request*>& batch);

  const nn::Mlp actor_;
  const nn::Normalizer observation_normalizer_, goal_normalizer_;
  const double clip_obs_;
  const int max_batch_;

  mutable std::mutex mutex_;
  std::condition_variable batch_done_;
  std::vector<Request*> waiting_;  // guarded by mutex_
  bool running_ = false;           // guarded by mutex_
  BatchStats stats_;               // guarded by mutex_

  // Used only by the caller running a batch (running_ makes it exclusive).
  std::vector<Request*> batch_;
  nn::Matrix input_;
  std::vector<nn::MlpWorkspace> workspaces_;  // [n - 1]: one per batch size
};

}  // namespace pnp::serving
