#include "robot/target_planner.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "robot/rate_limit.h"
#include "sim/world_layout.h"

namespace pnp::robot {

PlannedTarget plan_target(const GatewayConfig& config, const geometry::Pose& commanded_base,
                          double measured_gap_m, const sim::Action& action) {
  if (!geometry::is_finite(commanded_base)) {
    throw_invalid_argument("commanded pose", "finite values", "a non-finite pose");
  }
  if (!std::isfinite(measured_gap_m)) {
    throw_invalid_argument("gripper width", "a finite width", std::to_string(measured_gap_m));
  }
  const geometry::RigidTransform sim_from_base = config.base_from_sim.inverse();
  const geometry::Pose commanded_sim = sim_from_base.apply(commanded_base);

  PlannedTarget planned;
  planned.sim.orientation = commanded_sim.orientation;
  for (int k = 0; k < 3; ++k) {
    // std::clamp passes a NaN through, so check_target still sees and refuses it.
    planned.sim.position_m(k) =
        std::clamp(commanded_sim.position_m(k) + action(k) * config.action_scale_m,
                   sim::layout::kWorkspaceMin(k), sim::layout::kWorkspaceMax(k));
  }
  const double full_width = config.limits.gripper_max_width_m;
  planned.base.gripper_width_m = std::clamp(measured_gap_m + action(3) * full_width,
                                            config.limits.gripper_min_width_m, full_width);
  planned.base.pose = config.base_from_sim.apply(planned.sim);

  if (geometry::is_finite(planned.base.pose)) {
    const double max_step_m = std::min(config.limits.max_step_m,
                                       config.limits.max_speed_m_per_s * config.policy_period_s);
    const geometry::Pose limited = limit_step(commanded_base, planned.base.pose, max_step_m);
    planned.rate_limited = (limited.position_m - planned.base.pose.position_m).norm() > 0;
    planned.base.pose = limited;
    planned.sim = sim_from_base.apply(limited);
  }
  planned.verdict =
      check_target(config.limits, planned.base, commanded_base, config.policy_period_s);
  return planned;
}

}  // namespace pnp::robot
