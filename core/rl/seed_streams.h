#pragma once
// Independent random streams derived from a run's seed, one per purpose, so that
// evaluation episodes are never training episodes and a change in one stream (say, the
// number of evaluation episodes) never shifts another.

#include <cstdint>

#include "common/rng.h"

namespace pnp::rl {

enum class Stream : std::uint64_t {
  kNetworkInit = 1,
  kTrainingEpisodes = 2,  // environment seeds of training episodes
  kExploration = 3,       // action noise during training rollouts
  kReplaySampling = 4,
  kEvaluation = 5,   // the fixed evaluation episodes of the learning curve
  kHeldOutTest = 6,  // final held-out evaluation
};

inline std::uint64_t stream_seed(std::uint64_t run_seed, Stream stream) {
  return derive_seed(run_seed, 0x5EED0000ULL + static_cast<std::uint64_t>(stream));
}

}  // namespace pnp::rl
