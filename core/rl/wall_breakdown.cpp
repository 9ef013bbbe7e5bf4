#include "rl/wall_breakdown.h"

#include <algorithm>

namespace pnp::rl {

WallBreakdown PhaseClock::finish(WallBreakdown phases) const {
  const double total = std::chrono::duration<double>(Clock::now() - start_).count();
  const double accounted = phases.rollout_s + phases.update_s + phases.eval_s + phases.report_s;
  phases.other_s = std::max(0.0, total - accounted);
  phases.total_s = phases.phases_sum();
  return phases;
}

}  // namespace pnp::rl
