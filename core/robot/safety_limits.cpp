#include "robot/safety_limits.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "common/error.h"
#include "sim/panda_hand.h"

namespace pnp::robot {
namespace {

constexpr std::string_view kAxes = "xyz";

std::string vec(const Eigen::Vector3d& v) {
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", v.x(), v.y(), v.z());
}

void require_positive_finite(double value, std::string_view field, std::string_view unit) {
  if (!std::isfinite(value) || value <= 0) {
    throw_invalid_argument(field, fmt::format("a positive finite number ({})", unit),
                           fmt::format("{}", value));
  }
}

SafetyVerdict refuse(SafetyRefusal refusal, std::string reason) {
  return SafetyVerdict{refusal, std::move(reason)};
}

}  // namespace

void validate_workspace(const WorkspaceBox& box, double table_top_z_m, std::string_view prefix) {
  const std::string table_field = fmt::format("{}.table_top_z_m", prefix);
  if (!std::isfinite(table_top_z_m) || std::abs(table_top_z_m) > kPandaReach_m) {
    throw_invalid_argument(table_field,
                           fmt::format("a finite height within {} m of the base", kPandaReach_m),
                           fmt::format("{}", table_top_z_m));
  }
  for (Eigen::Index i = 0; i < 3; ++i) {
    const auto axis = static_cast<std::size_t>(i);
    const std::string min_field = fmt::format("{}.workspace.min_m[{}]", prefix, i);
    const std::string max_field = fmt::format("{}.workspace.max_m[{}]", prefix, i);
    if (!std::isfinite(box.min_m(i))) {
      throw_invalid_argument(min_field, "a finite number", fmt::format("{}", box.min_m(i)));
    }
    if (!std::isfinite(box.max_m(i))) {
      throw_invalid_argument(max_field, "a finite number", fmt::format("{}", box.max_m(i)));
    }
    if (box.min_m(i) >= box.max_m(i)) {
      throw_invalid_argument(min_field,
                             fmt::format("less than {}.workspace.max_m[{}] ({} m, the {} axis)",
                                         prefix, i, box.max_m(i), kAxes[axis]),
                             fmt::format("{}", box.min_m(i)));
    }
    if (i < 2) {  // horizontal: within the reach on both sides of the base
      for (const auto& [value, field] :
           {std::pair{box.min_m(i), min_field}, std::pair{box.max_m(i), max_field}}) {
        if (std::abs(value) > kPandaReach_m) {
          throw_invalid_argument(
              field,
              fmt::format("within the Panda's reach, |{}| <= {} m", kAxes[axis], kPandaReach_m),
              fmt::format("{}", value));
        }
      }
    }
  }
  const double floor = sim::lowest_grip_point_z(table_top_z_m);
  if (box.min_m.z() < floor) {
    throw_invalid_argument(
        fmt::format("{}.workspace.min_m[2]", prefix),
        fmt::format("at least {:.4f} m: the table top ({} m) + the pads' reach below the grip "
                    "point ({} m) + {} m clearance",
                    floor, table_top_z_m, sim::kPadReachBelowGripPoint_m, sim::kPadClearance_m),
        fmt::format("{}", box.min_m.z()));
  }
  const double ceiling = kPandaShoulderHeight_m + kPandaReach_m;
  if (box.max_m.z() > ceiling) {
    throw_invalid_argument(
        fmt::format("{}.workspace.max_m[2]", prefix),
        fmt::format("at most {} m: the shoulder's height plus the reach", ceiling),
        fmt::format("{}", box.max_m.z()));
  }
}

void SafetyLimits::validate() const {
  validate_workspace(workspace, table_top_z_m, "limits");
  require_positive_finite(max_step_m, "limits.max_step_m", "m");
  require_positive_finite(max_speed_m_per_s, "limits.max_speed_m_per_s", "m/s");
  require_positive_finite(max_rotation_step_rad, "limits.max_rotation_step_rad", "rad");
  if (!std::isfinite(gripper_min_width_m) || gripper_min_width_m < 0) {
    throw_invalid_argument("limits.gripper_min_width_m", "a finite width >= 0 m",
                           fmt::format("{}", gripper_min_width_m));
  }
  if (!std::isfinite(gripper_max_width_m) || gripper_max_width_m <= gripper_min_width_m) {
    throw_invalid_argument(
        "limits.gripper_max_width_m",
        fmt::format("a finite width greater than limits.gripper_min_width_m ({} m)",
                    gripper_min_width_m),
        fmt::format("{}", gripper_max_width_m));
  }
  // Below 1 so that a zero quaternion can never pass.
  if (!std::isfinite(quaternion_norm_tolerance) || quaternion_norm_tolerance <= 0 ||
      quaternion_norm_tolerance >= 1) {
    throw_invalid_argument("limits.quaternion_norm_tolerance", "a number in (0, 1)",
                           fmt::format("{}", quaternion_norm_tolerance));
  }
}

std::string_view safety_refusal_name(SafetyRefusal refusal) {
  switch (refusal) {
    case SafetyRefusal::kNonFinite:
      return "non_finite";
    case SafetyRefusal::kBadQuaternion:
      return "bad_quaternion";
    case SafetyRefusal::kOutsideWorkspace:
      return "outside_workspace";
    case SafetyRefusal::kStepTooLarge:
      return "step_too_large";
    case SafetyRefusal::kTooFast:
      return "too_fast";
    case SafetyRefusal::kRotationStepTooLarge:
      return "rotation_step_too_large";
    case SafetyRefusal::kGripperOutOfRange:
      return "gripper_out_of_range";
  }
  return "unknown";
}

SafetyVerdict check_target(const SafetyLimits& limits, const PoseTarget& target,
                           const geometry::Pose& previous_commanded, double period_s) {
  // The caller's own state and settings: a wrong one is a bug, not a policy output.
  limits.validate();
  const Eigen::Quaterniond& previous_q = previous_commanded.orientation;
  if (!geometry::is_finite(previous_commanded) ||
      std::abs(previous_q.norm() - 1.0) > limits.quaternion_norm_tolerance) {
    throw_invalid_argument("previous_commanded", "a finite pose with a unit quaternion",
                           fmt::format("position {} m, orientation (w {}, x {}, y {}, z {})",
                                       vec(previous_commanded.position_m), previous_q.w(),
                                       previous_q.x(), previous_q.y(), previous_q.z()));
  }
  if (!std::isfinite(period_s) || period_s <= 0) {
    throw_invalid_argument("period_s", "a positive finite duration (s)",
                           fmt::format("{}", period_s));
  }

  const Eigen::Vector3d& p = target.pose.position_m;
  const Eigen::Quaterniond& q = target.pose.orientation;
  if (!p.allFinite()) {
    return refuse(SafetyRefusal::kNonFinite, "target position " + vec(p) + " m is not finite");
  }
  if (!q.coeffs().allFinite()) {
    return refuse(SafetyRefusal::kNonFinite,
                  fmt::format("target orientation (w {}, x {}, y {}, z {}) is not finite", q.w(),
                              q.x(), q.y(), q.z()));
  }
  if (!std::isfinite(target.gripper_width_m)) {
    return refuse(SafetyRefusal::kNonFinite,
                  fmt::format("target gripper width {} m is not finite", target.gripper_width_m));
  }

  // From here on, comparisons are written to fail closed: a NaN refuses.
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) <= limits.quaternion_norm_tolerance)) {
    return refuse(SafetyRefusal::kBadQuaternion,
                  fmt::format("target orientation quaternion has norm {:.6g}, expected 1 within "
                              "{:g}",
                              norm, limits.quaternion_norm_tolerance));
  }

  const WorkspaceBox& box = limits.workspace;
  for (Eigen::Index i = 0; i < 3; ++i) {
    if (!(p(i) >= box.min_m(i) && p(i) <= box.max_m(i))) {
      return refuse(SafetyRefusal::kOutsideWorkspace,
                    fmt::format("position {} m outside workspace {} [{:.6g}, {:.6g}] m", vec(p),
                                kAxes[static_cast<std::size_t>(i)], box.min_m(i), box.max_m(i)));
    }
  }

  const double step_m = (p - previous_commanded.position_m).norm();
  if (!(step_m <= limits.max_step_m)) {
    return refuse(SafetyRefusal::kStepTooLarge,
                  fmt::format("step of {:.6g} m from the previous command exceeds max_step_m "
                              "{:g} m",
                              step_m, limits.max_step_m));
  }
  const double speed = step_m / period_s;
  if (!(speed <= limits.max_speed_m_per_s)) {
    return refuse(SafetyRefusal::kTooFast,
                  fmt::format("speed {:.6g} m/s ({:.6g} m in {:g} s) exceeds max_speed_m_per_s "
                              "{:g} m/s",
                              speed, step_m, period_s, limits.max_speed_m_per_s));
  }

  const double rotation_rad = geometry::rotation_angle_rad(previous_commanded.orientation, q);
  if (!(rotation_rad <= limits.max_rotation_step_rad)) {
    return refuse(SafetyRefusal::kRotationStepTooLarge,
                  fmt::format("rotation of {:.6g} rad from the previous command exceeds "
                              "max_rotation_step_rad {:g} rad",
                              rotation_rad, limits.max_rotation_step_rad));
  }

  if (!(target.gripper_width_m >= limits.gripper_min_width_m &&
        target.gripper_width_m <= limits.gripper_max_width_m)) {
    return refuse(
        SafetyRefusal::kGripperOutOfRange,
        fmt::format("gripper width {:.6g} m outside [{:g}, {:g}] m", target.gripper_width_m,
                    limits.gripper_min_width_m, limits.gripper_max_width_m));
  }
  return SafetyVerdict{};
}

}  // namespace pnp::robot
