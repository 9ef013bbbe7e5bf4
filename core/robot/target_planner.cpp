#include "robot/target_planner.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "robot/rate_limit.h"
#include "sim/world_layout.h"

namespace pnp::robot {
namespace {

// The opening the gripper is sent to: the environment's finger servo target, both fingers.
double gripper_width(const GatewayConfig& config, const sim::WorldParameters& world, double gap_m,
                     double action) {
  const double full_width = config.limits.gripper_max_width_m;
  const double per_unit = world.finger_action_in_metres ? 2.0 : full_width;
  return std::clamp(gap_m + action * per_unit, config.limits.gripper_min_width_m, full_width);
}

}  // namespace

PlannedTarget plan_target(const GatewayConfig& config, const sim::WorldParameters& world,
                          const ArmReading& arm, const sim::Action& action) {
  if (!geometry::is_finite(arm.commanded_base)) {
    throw_invalid_argument("commanded pose", "finite values", "a non-finite pose");
  }
  if (!geometry::is_finite(arm.measured_base)) {
    throw_invalid_argument("measured pose", "finite values", "a non-finite pose");
  }
  if (!arm.held_orientation_base.coeffs().allFinite() ||
      std::abs(arm.held_orientation_base.norm() - 1) > config.limits.quaternion_norm_tolerance) {
    throw_invalid_argument("held orientation", "a unit quaternion", "another value");
  }
  if (!std::isfinite(arm.gap_m)) {
    throw_invalid_argument("gripper width", "a finite width", std::to_string(arm.gap_m));
  }
  const geometry::RigidTransform sim_from_base = config.base_from_sim.inverse();
  const geometry::Pose commanded_sim = sim_from_base.apply(arm.commanded_base);
  const Eigen::Vector3d from = world.mocap == sim::MocapControl::kFromGripper
                                   ? sim_from_base.apply(arm.measured_base).position_m
                                   : commanded_sim.position_m;

  PlannedTarget planned;
  planned.sim.orientation =
      sim_from_base.apply(geometry::Pose{arm.commanded_base.position_m, arm.held_orientation_base})
          .orientation;
  for (int k = 0; k < 3; ++k) {
    // std::clamp passes a NaN through, so check_target still sees and refuses it.
    planned.sim.position_m(k) =
        std::clamp(from(k) + action(k) * config.action_scale_m, sim::layout::kWorkspaceMin(k),
                   sim::layout::kWorkspaceMax(k));
  }
  planned.base.gripper_width_m = gripper_width(config, world, arm.gap_m, action(3));
  planned.base.pose = config.base_from_sim.apply(planned.sim);
  Eigen::Vector3d& p = planned.base.pose.position_m;
  const WorkspaceBox& box = config.limits.workspace;
  const Eigen::Vector3d in_box = p.cwiseMax(box.min_m).cwiseMin(box.max_m);
  if (p.allFinite() && in_box != p) {
    p = in_box;
    planned.clamped = true;
  }

  if (geometry::is_finite(planned.base.pose)) {
    const double max_step_m = std::min(config.limits.max_step_m,
                                       config.limits.max_speed_m_per_s * config.policy_period_s);
    const geometry::Pose limited = limit_step(arm.commanded_base, planned.base.pose, max_step_m);
    planned.rate_limited = (limited.position_m - planned.base.pose.position_m).norm() > 0;
    planned.base.pose = limited;
    planned.sim = sim_from_base.apply(limited);
  }
  planned.verdict =
      check_target(config.limits, planned.base, arm.commanded_base, config.policy_period_s);
  return planned;
}

std::optional<PoseTarget> hold_target(const GatewayConfig& config,
                                      const std::optional<PoseTarget>& last_accepted,
                                      const geometry::Pose& commanded_base) {
  if (!last_accepted ||
      !check_target(config.limits, *last_accepted, commanded_base, config.policy_period_s).ok()) {
    return std::nullopt;
  }
  return last_accepted;
}

}  // namespace pnp::robot
