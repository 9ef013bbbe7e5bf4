#include "services/robot_controller/feedback_convert.h"

#include "common/error.h"
#include "services/common/robot_convert.h"

namespace pnp::services {

robot::v1::ControllerStatus to_proto(robot::ControllerStatus status) {
  using S = robot::ControllerStatus;
  switch (status) {
    case S::kOk:
      return robot::v1::CONTROLLER_STATUS_OK;
    case S::kInvalidTarget:
      return robot::v1::CONTROLLER_STATUS_INVALID_TARGET;
    case S::kUnreachable:
      return robot::v1::CONTROLLER_STATUS_UNREACHABLE;
    case S::kJointLimit:
      return robot::v1::CONTROLLER_STATUS_JOINT_LIMIT;
    case S::kStopped:
      return robot::v1::CONTROLLER_STATUS_STOPPED;
    case S::kLeaseLost:
      return robot::v1::CONTROLLER_STATUS_LEASE_LOST;
    case S::kOutsideLimits:
      return robot::v1::CONTROLLER_STATUS_OUTSIDE_LIMITS;
    case S::kStale:
      return robot::v1::CONTROLLER_STATUS_STALE;
  }
  throw_internal("unknown controller status");
}

robot::v1::StopKind to_proto(robot::StopKind kind) {
  switch (kind) {
    case robot::StopKind::kNone:
      return robot::v1::STOP_KIND_UNSPECIFIED;
    case robot::StopKind::kProtective:
      return robot::v1::STOP_KIND_PROTECTIVE;
    case robot::StopKind::kEmergency:
      return robot::v1::STOP_KIND_EMERGENCY;
  }
  throw_internal("unknown stop kind");
}

robot::StopKind stop_kind_from_proto(robot::v1::StopKind kind) {
  switch (kind) {
    case robot::v1::STOP_KIND_PROTECTIVE:
      return robot::StopKind::kProtective;
    case robot::v1::STOP_KIND_UNSPECIFIED:  // a stop that does not say is the safe kind
    case robot::v1::STOP_KIND_EMERGENCY:
      return robot::StopKind::kEmergency;
    default:
      throw_invalid_argument("kind", "STOP_KIND_EMERGENCY or STOP_KIND_PROTECTIVE",
                             std::to_string(static_cast<int>(kind)));
  }
}

robot::v1::ControllerMode to_proto(robot::ArmMode mode) {
  using M = robot::ArmMode;
  switch (mode) {
    case M::kIdle:
      return robot::v1::CONTROLLER_MODE_IDLE;
    case M::kTracking:
      return robot::v1::CONTROLLER_MODE_TRACKING;
    case M::kHolding:
      return robot::v1::CONTROLLER_MODE_HOLDING;
    case M::kStopped:
      return robot::v1::CONTROLLER_MODE_STOPPED;
    case M::kFault:
      return robot::v1::CONTROLLER_MODE_FAULT;
  }
  throw_internal("unknown arm mode");
}

void to_proto(const robot::ControllerReport& report, const std::string& frame_id,
              robot::v1::ControllerFeedback& out) {
  const auto now = std::chrono::system_clock::now();
  out.set_sequence(report.sequence);
  to_proto(now, *out.mutable_stamp());
  out.set_frame_id(frame_id);
  to_proto(report.arm.tcp_base, *out.mutable_measured());
  to_proto(report.arm.commanded_base, *out.mutable_commanded());
  out.set_gripper_width_m(report.arm.finger_gap_m);
  if (report.arm.object_base) {
    to_proto(*report.arm.object_base, *out.mutable_object()->mutable_pose());
    to_proto(now, *out.mutable_object()->mutable_stamp());
  } else {
    out.clear_object();
  }
  out.set_mode(to_proto(report.arm.mode));
  out.set_status(to_proto(report.status));
  out.clear_errors();
  for (const auto& e : report.errors) out.add_errors(e);
  out.clear_joint_positions_rad();
  for (double q : report.arm.joint_positions_rad) out.add_joint_positions_rad(q);
}

}  // namespace pnp::services
