#pragma once
// pnp.robot.v1.RobotControllerService over any controller (robot::ArmController: the
// simulated Panda's in pnp-robot-sim, a Franka's in pnp-franka-bridge): the protocol's
// messages in, the controller's reports out.
// A drive stream must open with a valid lease; each target is answered by exactly one
// feedback message; a bad target is a status in its feedback, never a broken stream. A
// new stream cancels the one before it. Stops and their clearing are logged with who and
// why.

#include <mutex>
#include <string>

#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "robot/arm_controller.h"
#include "services/common/stream_limits.h"

namespace pnp::services {

// Who clears a stop, as logged and as the controller records it. Under an access policy it
// is the caller's authenticated principal, whatever name the request states (kept beside
// it in the log), so nobody can clear an emergency stop in another operator's name;
// without a policy (`principal` empty) it is the name the request states.
std::string clearing_operator(const std::string& principal, const std::string& stated);

// INVALID_ARGUMENT for an empty lease id, naming the field.
void require_lease_id(const std::string& lease_id);

class RobotControllerServiceImpl final : public robot::v1::RobotControllerService::Service {
 public:
  // `limits` (null: none) bounds the pose streams; it must outlive the service.
  explicit RobotControllerServiceImpl(robot::ArmController& arm, StreamLimits* limits = nullptr)
      : arm_(arm), limits_(limits) {}

  grpc::Status AcquireLease(grpc::ServerContext* context,
                            const robot::v1::AcquireLeaseRequest* request,
                            robot::v1::AcquireLeaseResponse* response) override;
  grpc::Status ReleaseLease(grpc::ServerContext* context,
                            const robot::v1::ReleaseLeaseRequest* request,
                            robot::v1::ReleaseLeaseResponse* response) override;
  grpc::Status StreamPoseTargets(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<robot::v1::ControllerFeedback, robot::v1::StreamPoseTargetsRequest>*
          stream) override;
  grpc::Status GetState(grpc::ServerContext* context, const robot::v1::GetStateRequest* request,
                        robot::v1::GetStateResponse* response) override;
  grpc::Status Stop(grpc::ServerContext* context, const robot::v1::StopRequest* request,
                    robot::v1::StopResponse* response) override;
  grpc::Status Resume(grpc::ServerContext* context, const robot::v1::ResumeRequest* request,
                      robot::v1::ResumeResponse* response) override;

 private:
  robot::ArmController& arm_;
  StreamLimits* limits_;
  std::mutex stream_mutex_;
  grpc::ServerContext* current_stream_ = nullptr;  // guarded by stream_mutex_
};

}  // namespace pnp::services
