#pragma once
// Rate limiting of pose commands, as libfranka's limitRate does for its own commands: a
// target further than the allowed distance from the previous command is moved back onto
// the straight line towards it, so the arm gets there over several cycles instead of
// being refused (or jerked). Use it before check_target with
// min(max_step_m, max_speed_m_per_s * period_s).

#include "geometry/pose.h"

namespace pnp::robot {

// `to`, with its position moved towards `from` until it is at most `max_distance_m` away;
// the orientation is `to`'s, untouched (check_target bounds rotation steps separately).
// INVALID_ARGUMENT for a non-finite pose or a `max_distance_m` that is not positive and
// finite.
geometry::Pose limit_step(const geometry::Pose& from, const geometry::Pose& to,
                          double max_distance_m);

}  // namespace pnp::robot
