#include "robot/controller_limits.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "robot/arm_backend.h"
#include "robot/json_fields.h"

namespace pnp::robot {
namespace {

using nlohmann::json;
using namespace robot::json_fields;

void require_positive_finite(double value, std::string_view field, std::string_view unit) {
  if (!std::isfinite(value) || value <= 0) {
    throw_invalid_argument(field, fmt::format("a positive finite number ({})", unit),
                           fmt::format("{}", value));
  }
}

std::string vec(const Eigen::Vector3d& v) {
  return fmt::format("({:.4f}, {:.4f}, {:.4f})", v.x(), v.y(), v.z());
}

}  // namespace

void ControllerLimits::validate() const {
  robot::validate_workspace(workspace, table_top_z_m, "controller");
  require_positive_finite(max_step_m, "controller.max_step_m", "m");
  require_positive_finite(max_rotation_step_rad, "controller.max_rotation_step_rad", "rad");
  require_positive_finite(max_speed_m_per_s, "controller.max_speed_m_per_s", "m/s");
  require_positive_finite(max_target_age_s, "controller.max_target_age_s", "s");
}

ControllerLimits ControllerLimits::from_json(const json& j) {
  require_object(j, "controller",
                 {"workspace", "table_top_z_m", "max_step_m", "max_rotation_step_rad",
                  "max_speed_m_per_s", "max_target_age_s"});
  ControllerLimits l;
  if (const auto ws = j.find("workspace"); ws != j.end()) {
    require_object(*ws, "controller.workspace", {"min_m", "max_m"});
    read_vector3(*ws, "min_m", "controller.workspace", l.workspace.min_m);
    read_vector3(*ws, "max_m", "controller.workspace", l.workspace.max_m);
  }
  read_number(j, "table_top_z_m", "controller", l.table_top_z_m);
  read_number(j, "max_step_m", "controller", l.max_step_m);
  read_number(j, "max_rotation_step_rad", "controller", l.max_rotation_step_rad);
  read_number(j, "max_speed_m_per_s", "controller", l.max_speed_m_per_s);
  read_number(j, "max_target_age_s", "controller", l.max_target_age_s);
  l.validate();
  return l;
}

ControllerLimits ControllerLimits::load(const std::filesystem::path& path) {
  const json j = read_file(path, "controller config");
  try {
    return from_json(j);
  } catch (const Error& e) {
    throw Error(e.code(), fmt::format("{}: {}", path.string(), e.what()));
  }
}

json ControllerLimits::to_json() const {
  return {{"workspace",
           {{"min_m", vector3_json(workspace.min_m)}, {"max_m", vector3_json(workspace.max_m)}}},
          {"table_top_z_m", table_top_z_m},
          {"max_step_m", max_step_m},
          {"max_rotation_step_rad", max_rotation_step_rad},
          {"max_speed_m_per_s", max_speed_m_per_s},
          {"max_target_age_s", max_target_age_s}};
}

std::optional<std::string> ControllerLimits::refusal(const geometry::Pose& target_base,
                                                     const geometry::Pose& commanded_base) const {
  const Eigen::Vector3d& position_base_m = target_base.position_m;
  if (!position_base_m.allFinite()) return std::nullopt;
  if (!workspace.contains(position_base_m)) {
    return fmt::format("position: {} m is outside the controller's workspace {} .. {} m",
                       vec(position_base_m), vec(workspace.min_m), vec(workspace.max_m));
  }
  const double step = (position_base_m - commanded_base.position_m).norm();
  if (!(step <= max_step_m)) {
    return fmt::format(
        "position: {:.4f} m from the commanded pose, more than the controller's "
        "max_step_m {} m",
        step, max_step_m);
  }
  // Only a unit quaternion has a turn to measure; anything else is the arm's to refuse.
  const Eigen::Vector4d q = target_base.orientation.coeffs();
  if (q.allFinite() && std::abs(q.norm() - 1.0) <= kUnitQuaternionTolerance) {
    const double turn = target_base.orientation.normalized().angularDistance(
        commanded_base.orientation.normalized());
    if (!(turn <= max_rotation_step_rad)) {
      return fmt::format(
          "orientation: {:.4f} rad from the commanded orientation, more than the controller's "
          "max_rotation_step_rad {} rad",
          turn, max_rotation_step_rad);
    }
  }
  return std::nullopt;
}

double ControllerLimits::capped_speed(double requested_m_per_s, double default_m_per_s) const {
  return std::min(requested_m_per_s > 0 ? requested_m_per_s : default_m_per_s, max_speed_m_per_s);
}

}  // namespace pnp::robot
