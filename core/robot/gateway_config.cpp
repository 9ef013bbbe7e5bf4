#include "robot/gateway_config.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "common/error.h"
#include "common/validate.h"
#include "robot/json_fields.h"

namespace pnp::robot {
namespace {

using nlohmann::json;
using namespace json_fields;

SafetyLimits limits_from_json(const json& j) {
  constexpr std::string_view p = "limits";
  require_object(
      j, p,
      {"workspace", "table_top_z_m", "max_step_m", "max_speed_m_per_s", "max_rotation_step_rad",
       "gripper_min_width_m", "gripper_max_width_m", "quaternion_norm_tolerance"});
  SafetyLimits limits;
  if (const auto ws = j.find("workspace"); ws != j.end()) {
    constexpr std::string_view wp = "limits.workspace";
    require_object(*ws, wp, {"min_m", "max_m"});
    read_vector3(*ws, "min_m", wp, limits.workspace.min_m);
    read_vector3(*ws, "max_m", wp, limits.workspace.max_m);
  }
  read_number(j, "table_top_z_m", p, limits.table_top_z_m);
  read_number(j, "max_step_m", p, limits.max_step_m);
  read_number(j, "max_speed_m_per_s", p, limits.max_speed_m_per_s);
  read_number(j, "max_rotation_step_rad", p, limits.max_rotation_step_rad);
  read_number(j, "gripper_min_width_m", p, limits.gripper_min_width_m);
  read_number(j, "gripper_max_width_m", p, limits.gripper_max_width_m);
  read_number(j, "quaternion_norm_tolerance", p, limits.quaternion_norm_tolerance);
  return limits;
}

void require_positive_finite(double value, std::string_view field, std::string_view unit) {
  if (!std::isfinite(value) || value <= 0) {
    throw_invalid_argument(field, fmt::format("a positive finite number ({})", unit),
                           fmt::format("{}", value));
  }
}

}  // namespace

GatewayConfig GatewayConfig::from_json(const json& j) {
  require_object(j, "",
                 {"base_from_sim", "base_frame_id", "limits", "policy_period_s",
                  "deadman_timeout_s", "lease_timeout_s", "max_episode_steps", "action_scale_m",
                  "arrival_tolerance_m", "max_arrival_wait_periods"});
  GatewayConfig c;
  const auto transform = j.find("base_from_sim");
  if (transform == j.end()) {
    throw Error(ErrorCode::kInvalidArgument,
                "base_from_sim: missing (required, a row-major 4x4 matrix: the frame "
                "calibration has no default)");
  }
  c.base_from_sim = geometry::RigidTransform::from_json(*transform, "base_from_sim");
  read_string(j, "base_frame_id", "", c.base_frame_id);
  if (const auto limits = j.find("limits"); limits != j.end()) c.limits = limits_from_json(*limits);
  read_number(j, "policy_period_s", "", c.policy_period_s);
  read_number(j, "deadman_timeout_s", "", c.deadman_timeout_s);
  read_number(j, "lease_timeout_s", "", c.lease_timeout_s);
  read_int(j, "max_episode_steps", "", c.max_episode_steps);
  read_number(j, "action_scale_m", "", c.action_scale_m);
  read_number(j, "arrival_tolerance_m", "", c.arrival_tolerance_m);
  read_int(j, "max_arrival_wait_periods", "", c.max_arrival_wait_periods);
  c.validate();
  return c;
}

GatewayConfig GatewayConfig::load(const std::filesystem::path& path) {
  const json j = read_file(path, "gateway config");
  try {
    return from_json(j);
  } catch (const Error& e) {
    throw Error(e.code(), fmt::format("{}: {}", path.string(), e.what()));
  }
}

json GatewayConfig::to_json() const {
  const SafetyLimits& l = limits;
  return {
      {"base_from_sim", base_from_sim.to_json()},
      {"base_frame_id", base_frame_id},
      {"limits",
       {{"workspace",
         {{"min_m", vector3_json(l.workspace.min_m)}, {"max_m", vector3_json(l.workspace.max_m)}}},
        {"table_top_z_m", l.table_top_z_m},
        {"max_step_m", l.max_step_m},
        {"max_speed_m_per_s", l.max_speed_m_per_s},
        {"max_rotation_step_rad", l.max_rotation_step_rad},
        {"gripper_min_width_m", l.gripper_min_width_m},
        {"gripper_max_width_m", l.gripper_max_width_m},
        {"quaternion_norm_tolerance", l.quaternion_norm_tolerance}}},
      {"policy_period_s", policy_period_s},
      {"deadman_timeout_s", deadman_timeout_s},
      {"lease_timeout_s", lease_timeout_s},
      {"max_episode_steps", max_episode_steps},
      {"action_scale_m", action_scale_m},
      {"arrival_tolerance_m", arrival_tolerance_m},
      {"max_arrival_wait_periods", max_arrival_wait_periods}};
}

void GatewayConfig::validate() const {
  limits.validate();
  if (base_frame_id.empty()) throw_invalid_argument("base_frame_id", "a frame name", "\"\"");
  require_positive_finite(policy_period_s, "policy_period_s", "s");
  require_positive_finite(deadman_timeout_s, "deadman_timeout_s", "s");
  if (deadman_timeout_s <= policy_period_s) {
    throw_invalid_argument(
        "deadman_timeout_s",
        fmt::format("more than policy_period_s ({} s), or it trips every cycle", policy_period_s),
        fmt::format("{}", deadman_timeout_s));
  }
  if (!std::isfinite(lease_timeout_s) || lease_timeout_s <= deadman_timeout_s ||
      lease_timeout_s > 10) {
    throw_invalid_argument(
        "lease_timeout_s",
        fmt::format("more than deadman_timeout_s ({} s) and at most 10 s", deadman_timeout_s),
        fmt::format("{}", lease_timeout_s));
  }
  if (max_episode_steps <= 0 || max_episode_steps > sim::layout::kMaxEpisodeSteps) {
    throw_invalid_argument("max_episode_steps",
                           fmt::format("1 to {} steps", sim::layout::kMaxEpisodeSteps),
                           std::to_string(max_episode_steps));
  }
  require_positive_finite(action_scale_m, "action_scale_m", "m");
  if (action_scale_m > limits.max_step_m) {
    throw_invalid_argument(
        "action_scale_m",
        fmt::format("at most limits.max_step_m ({} m), or a full action is refused",
                    limits.max_step_m),
        fmt::format("{}", action_scale_m));
  }
  if (!(arrival_tolerance_m > 0 && arrival_tolerance_m <= 0.1)) {
    throw_invalid_argument("arrival_tolerance_m", "a distance in (0, 0.1] m",
                           fmt::format("{}", arrival_tolerance_m));
  }
  if (max_arrival_wait_periods < 0 || max_arrival_wait_periods > kMaxArrivalWaitPeriods) {
    throw_invalid_argument("max_arrival_wait_periods",
                           fmt::format("an integer in [0, {}]", kMaxArrivalWaitPeriods),
                           std::to_string(max_arrival_wait_periods));
  }
}

}  // namespace pnp::robot
