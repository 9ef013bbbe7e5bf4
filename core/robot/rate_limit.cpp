#include "robot/rate_limit.h"

#include <fmt/format.h>

#include <cmath>

#include "common/error.h"

namespace pnp::robot {

geometry::Pose limit_step(const geometry::Pose& from, const geometry::Pose& to,
                          double max_distance_m) {
  if (!std::isfinite(max_distance_m) || max_distance_m <= 0) {
    throw_invalid_argument("max_distance_m", "a positive finite distance (m)",
                           fmt::format("{}", max_distance_m));
  }
  if (!geometry::is_finite(from)) throw_invalid_argument("from", "a finite pose", "a NaN or inf");
  if (!geometry::is_finite(to)) throw_invalid_argument("to", "a finite pose", "a NaN or inf");
  const Eigen::Vector3d step = to.position_m - from.position_m;
  const double distance = step.norm();
  if (distance <= max_distance_m) return to;
  // A hair short of the limit, so that rounding never makes the clipped step fail a check
  // against the same limit (check_target's max_step_m, or max_speed_m_per_s * period_s).
  constexpr double kRoundingMargin = 1e-12;
  const double scale = max_distance_m / distance * (1 - kRoundingMargin);
  return geometry::Pose{from.position_m + step * scale, to.orientation};
}

}  // namespace pnp::robot
