#pragma once
// Independent random streams derived from a run's seed, one per purpose, so that
// evaluation episodes are never training episodes and a change in one stream (say, the
// number of evaluation episodes) never shifts another.

#include <cstddef>
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

// The base seed of evaluation round `round` (0, 1, ...): the evaluation stream itself for
// the same scenes every round, or a seed derived from it and the round for new scenes each
// round. Either way evaluation scenes never come from the training stream.
inline std::uint64_t evaluation_round_seed(std::uint64_t eval_stream, bool fresh_each_round,
                                           std::size_t round) {
  return fresh_each_round ? derive_seed(eval_stream, 1 + static_cast<std::uint64_t>(round))
                          : eval_stream;
}

}  // namespace pnp::rl
