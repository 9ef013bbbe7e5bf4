#pragma once
// How many gradient steps a training cycle gets: the original's fixed number per cycle,
// or (updates_per_transition > 0) that many per transition the cycle stored, with the
// fractions carried over between cycles so that the long-run ratio is exact.

#include <cstddef>

#include "rl/ddpg_her_config.h"

namespace pnp::rl {

class UpdateSchedule {
 public:
  explicit UpdateSchedule(const DdpgHerConfig& config) : config_(config) {}
  int updates_for(std::size_t stored_transitions);

 private:
  DdpgHerConfig config_;
  double credit_ = 0;
};

}  // namespace pnp::rl
