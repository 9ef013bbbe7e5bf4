// robot status, stop and resume: an operator's view of the arm's controller. Clearing an
// emergency stop is an operator action that repeats the stop's reason word for word.
#include <nlohmann/json.hpp>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/rpc.h"
#include "common/error.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"

namespace pnp::pnpctl {
namespace {

namespace rv1 = robot::v1;

std::unique_ptr<rv1::RobotControllerService::Stub> controller(const Endpoints& endpoints) {
  return rv1::RobotControllerService::NewStub(endpoints.channel(endpoints.robot_controller));
}

std::string stop_kind(rv1::StopKind kind) {
  switch (kind) {
    case rv1::STOP_KIND_EMERGENCY:
      return "emergency";
    case rv1::STOP_KIND_PROTECTIVE:
      return "protective";
    default:
      return "none";
  }
}

}  // namespace

int robot_status_command(const Endpoints& endpoints, bool json) {
  rv1::GetStateResponse r;
  check(
      controller(endpoints)->GetState(context_with_deadline(std::chrono::seconds(5)).get(), {}, &r),
      "GetState", endpoints.robot_controller);
  const auto& p = r.state().commanded().position();
  const nlohmann::json out = {{"mode", rv1::ControllerMode_Name(r.state().mode())},
                              {"lease_holder", r.lease_holder()},
                              {"stop_kind", stop_kind(r.stop_kind())},
                              {"stop_reason", r.stop_reason()},
                              {"tcp_from_flange_m", r.tcp_from_flange_m()},
                              {"commanded_m", {p.x_m(), p.y_m(), p.z_m()}},
                              {"gripper_width_m", r.state().gripper_width_m()},
                              {"lockstep", r.lockstep()}};
  if (json) {
    std::printf("%s\n", out.dump().c_str());
    return 0;
  }
  std::printf("mode %s, lease %s, grip point %.4f m from the flange\n",
              rv1::ControllerMode_Name(r.state().mode()).c_str(),
              r.lease_holder().empty() ? "free" : ("held by " + r.lease_holder()).c_str(),
              r.tcp_from_flange_m());
  if (r.stop_kind() != rv1::STOP_KIND_UNSPECIFIED) {
    std::printf("%s stop: %s\n", stop_kind(r.stop_kind()).c_str(), r.stop_reason().c_str());
    if (r.stop_kind() == rv1::STOP_KIND_EMERGENCY) {
      std::printf("clear it, once the cell is safe: pnpctl robot resume --ack '%s'\n",
                  r.stop_reason().c_str());
    }
  }
  return 0;
}

int robot_stop_command(const Endpoints& endpoints, const std::string& reason) {
  if (reason.empty()) throw_invalid_argument("--reason", "why the arm is stopped", "\"\"");
  rv1::StopRequest request;
  request.set_reason(reason);
  request.set_kind(rv1::STOP_KIND_EMERGENCY);
  rv1::StopResponse response;
  check(controller(endpoints)->Stop(context_with_deadline(std::chrono::seconds(2)).get(), request,
                                    &response),
        "Stop", endpoints.robot_controller);
  std::printf("emergency stop: %s (mode %s)\n", reason.c_str(),
              rv1::ControllerMode_Name(response.state().mode()).c_str());
  return 0;
}

int robot_resume_command(const Endpoints& endpoints, const std::string& acknowledged_reason,
                         const std::string& operator_name) {
  if (operator_name.empty()) {
    throw_invalid_argument("--operator", "who clears the stop (or $USER set)", "\"\"");
  }
  rv1::ResumeRequest request;
  request.set_acknowledged_reason(acknowledged_reason);
  request.set_operator_name(operator_name);
  rv1::ResumeResponse response;
  check(controller(endpoints)->Resume(context_with_deadline(std::chrono::seconds(5)).get(), request,
                                      &response),
        "Resume", endpoints.robot_controller);
  std::printf("cleared the %s stop \"%s\" (operator %s); the arm holds its pose\n",
              stop_kind(response.cleared_kind()).c_str(), response.cleared_reason().c_str(),
              operator_name.c_str());
  return 0;
}

}  // namespace pnp::pnpctl
