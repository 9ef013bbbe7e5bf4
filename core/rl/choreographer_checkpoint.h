#pragma once
// The choreographer on disk: metadata as JSON, every parameter block in the network's
// fixed order, and the input normaliser's statistics, in the checksummed container of
// nn/checkpoint_io.h (a truncated or corrupted file is refused).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "rl/choreographer_net.h"

namespace pnp::rl {

struct ChoreographerMeta {
  std::string robot, object;
  std::string world = "paper";  // sim/world_profile.h (checkpoints before profiles: paper)
  ChoreographerSpec network;
  long long train_env_steps = 0;
  double eval_success = 0;
  std::uint64_t seed = 0;
  std::string code_commit;
  std::string gemm_path{};          // nn/gemm_path.h: which products computed it ("" before kept)
  std::string actuation = "mocap";  // sim/actuation.h (checkpoints before it: mocap)
};

struct LoadedChoreographer {
  ChoreographerMeta meta;
  ChoreographerNet net;
};

std::vector<std::uint8_t> save_choreographer(const ChoreographerMeta& meta, ChoreographerNet& net);
// Throws DATA_LOSS for a corrupted or truncated file, INVALID_ARGUMENT for an intact file
// of another kind.
LoadedChoreographer load_choreographer(std::span<const std::uint8_t> bytes);

}  // namespace pnp::rl
