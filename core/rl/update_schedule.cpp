#include "rl/update_schedule.h"

#include <cmath>

namespace pnp::rl {

int UpdateSchedule::updates_for(std::size_t stored_transitions) {
  if (config_.updates_per_transition <= 0) return config_.updates_per_cycle;
  credit_ += config_.updates_per_transition * static_cast<double>(stored_transitions);
  const double whole = std::floor(credit_);
  credit_ -= whole;
  return static_cast<int>(whole);
}

}  // namespace pnp::rl
