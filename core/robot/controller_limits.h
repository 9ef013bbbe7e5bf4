#pragma once
// The controller's own limits: what the arm side enforces whatever its network client
// sends, loaded from the controller's config file (deploy/robot/controller.json) and never
// settable over the network. A gateway checks targets too (robot/safety_limits.h); this is
// the second line, so a client that bypasses the gateway, or a gateway with a wrong
// config, still cannot drive the hand through the table, across the cell in one target,
// or faster than the arm's Cartesian limit.
//
//   {"workspace": {"min_m": [x, y, z], "max_m": [x, y, z]}, "table_top_z_m": 0,
//    "max_step_m": 0.15, "max_rotation_step_rad": 0.3, "max_speed_m_per_s": 1.7,
//    "max_target_age_s": 0.25}
//
// Every key may be left out (the defaults below); unknown keys are refused.

#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "geometry/pose.h"
#include "robot/safety_limits.h"

namespace pnp::robot {

struct ControllerLimits {
  // The gateway's default box (SafetyLimits) widened by 4 cm in x and y and 2 cm
  // upwards: the controller's box contains the gateway's, so the gateway's check refuses
  // first and this one only catches what gets past it. Its floor is the lowest grip point
  // that keeps the pads off the table.
  WorkspaceBox workspace{{0.10, -0.42, 0.013}, {0.74, 0.42, 0.50}};
  double table_top_z_m = 0.0;  // in the base frame
  // From the pose the motion generator commands now: a policy step is at most 8.7 cm.
  double max_step_m = 0.15;
  // From the orientation commanded now: the policy never turns the hand, so a larger turn
  // in one target is a fault (a flipped quaternion, a wrong frame). Wider than the
  // gateway's 0.2 rad (SafetyLimits), so the gateway refuses first.
  double max_rotation_step_rad = 0.3;
  // The Panda's Cartesian translation limit (Franka's datasheet); a client's
  // max_speed_m_per_s is capped to it.
  double max_speed_m_per_s = 1.7;
  // A target stamped longer ago than this (or this far in the future: clock skew) is
  // stale: it answers a state of the arm that has since changed. Real time only: in
  // lockstep the physics waits for each target.
  double max_target_age_s = 0.25;

  // INVALID_ARGUMENT naming the key (robot::validate_workspace for the box; positive,
  // finite values for the others).
  void validate() const;
  static ControllerLimits from_json(const nlohmann::json& json);
  static ControllerLimits load(const std::filesystem::path& path);  // errors name the path
  nlohmann::json to_json() const;

  // Why `target_base` may not be commanded from `commanded_base`, naming the limit;
  // nullopt when it may. A position that is not finite, or an orientation that is not a
  // unit quaternion, is left to the arm to refuse as an invalid target.
  std::optional<std::string> refusal(const geometry::Pose& target_base,
                                     const geometry::Pose& commanded_base) const;
  // The speed a segment is driven at: the client's (0: the arm's default), capped.
  double capped_speed(double requested_m_per_s, double default_m_per_s) const;
};

}  // namespace pnp::robot
