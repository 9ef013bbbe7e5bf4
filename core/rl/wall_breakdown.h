#pragma once
// Measures a training run's wall time by phase (common/wall_breakdown.h says what each
// phase holds), in seconds of this process's part of the run: a resumed run starts it
// again at zero.

#include <chrono>

#include "common/wall_breakdown.h"

namespace pnp::rl {

// Accumulates one phase's wall time: add(phase, since) after each stretch of it.
class PhaseClock {
 public:
  using Clock = std::chrono::steady_clock;
  PhaseClock() : start_(Clock::now()) {}
  static void add(double& phase, Clock::time_point since) {
    phase += std::chrono::duration<double>(Clock::now() - since).count();
  }
  // The breakdown with `other` the time no phase accounted for (never negative).
  WallBreakdown finish(WallBreakdown phases) const;

 private:
  Clock::time_point start_;
};

}  // namespace pnp::rl
