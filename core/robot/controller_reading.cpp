#include "robot/controller_reading.h"

#include <fmt/format.h>

#include <cmath>

namespace pnp::robot {
namespace {

std::optional<std::string> pose_error(const geometry::Pose& pose, std::string_view field,
                                      double tolerance) {
  if (!pose.position_m.allFinite()) {
    return fmt::format("{}.position: expected finite coordinates, got ({}, {}, {})", field,
                       pose.position_m.x(), pose.position_m.y(), pose.position_m.z());
  }
  const double norm = pose.orientation.norm();
  if (!pose.orientation.coeffs().allFinite() || std::abs(norm - 1) > tolerance) {
    return fmt::format(
        "{}.orientation: expected a unit quaternion (norm within {} of 1), got "
        "norm {}",
        field, tolerance, norm);
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> reading_error(const ControllerReading& reading,
                                         const std::string& frame_id,
                                         double quaternion_norm_tolerance) {
  if (reading.frame_id != frame_id) {
    return fmt::format("frame_id: expected \"{}\", got \"{}\"", frame_id, reading.frame_id);
  }
  if (auto e = pose_error(reading.measured_base, "measured", quaternion_norm_tolerance)) return e;
  if (auto e = pose_error(reading.commanded_base, "commanded", quaternion_norm_tolerance)) return e;
  if (!std::isfinite(reading.gripper_width_m)) {
    return fmt::format("gripper_width_m: expected a finite width, got {}", reading.gripper_width_m);
  }
  if (!reading.object_base) {
    return "object: the controller reports no perception of the object; an episode needs it";
  }
  return pose_error(*reading.object_base, "object.pose", quaternion_norm_tolerance);
}

}  // namespace pnp::robot
