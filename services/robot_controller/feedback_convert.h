#pragma once
// A controller's reports (robot::ArmController) as pnp.robot.v1 feedback.

#include <string>

#include "pnp/robot/v1/robot_controller.pb.h"
#include "robot/arm_controller.h"

namespace pnp::services {

robot::v1::ControllerStatus to_proto(robot::ControllerStatus status);
robot::v1::ControllerMode to_proto(robot::ArmMode mode);
robot::v1::StopKind to_proto(robot::StopKind kind);
// UNSPECIFIED reads as emergency; INVALID_ARGUMENT for a value outside the enum.
robot::StopKind stop_kind_from_proto(robot::v1::StopKind kind);

// The feedback for a report, in `frame_id`, with the object's pose when the arm perceives
// it (the stand-in always: its "perception").
void to_proto(const robot::ControllerReport& report, const std::string& frame_id,
              robot::v1::ControllerFeedback& out);

}  // namespace pnp::services
