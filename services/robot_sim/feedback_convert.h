#pragma once
// The arm stand-in's reports as pnp.robot.v1 feedback.

#include <string>

#include "arm_sim/controller_stand_in.h"
#include "pnp/robot/v1/robot_controller.pb.h"

namespace pnp::services {

robot::v1::ControllerStatus to_proto(arm_sim::ControllerStatus status);
robot::v1::ControllerMode to_proto(arm_sim::ArmMode mode);
robot::v1::StopKind to_proto(arm_sim::StopKind kind);
// UNSPECIFIED reads as emergency; INVALID_ARGUMENT for a value outside the enum.
arm_sim::StopKind stop_kind_from_proto(robot::v1::StopKind kind);

// The feedback for a report, in `frame_id`, with the object's pose (the stand-in's
// "perception").
void to_proto(const arm_sim::ControllerReport& report, const std::string& frame_id,
              robot::v1::ControllerFeedback& out);

}  // namespace pnp::services
