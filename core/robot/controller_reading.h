#pragma once
// One cycle's reading of the arm's controller, checked as a whole before anything is
// planned from it: a NaN in the commanded pose, a zero quaternion from a controller
// without perception or a reading in another frame must end the episode with the reason,
// not reach the planner or the policy.

#include <optional>
#include <string>

#include "geometry/pose.h"

namespace pnp::robot {

struct ControllerReading {
  std::string frame_id;
  geometry::Pose measured_base;
  geometry::Pose commanded_base;
  double gripper_width_m = 0;
  std::optional<geometry::Pose> object_base;  // absent: no perception of the object
};

// Why `reading` cannot drive a cycle, naming the field and the expected value: a frame
// other than `frame_id`, non-finite values, quaternions off unit norm by more than
// `quaternion_norm_tolerance`, a missing object. nullopt when it can.
std::optional<std::string> reading_error(const ControllerReading& reading,
                                         const std::string& frame_id,
                                         double quaternion_norm_tolerance);

}  // namespace pnp::robot
