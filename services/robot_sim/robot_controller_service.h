#pragma once
// pnp.robot.v1.RobotControllerService over any controller (robot::ArmController: the
// simulated Panda's, a Franka's through the bridge) and SimulatedSceneService over the
// stand-in (arm_sim::ControllerStandIn): the protocol's messages in, the reports out.
// A drive stream must open with a valid lease; each target is answered by exactly one
// feedback message; a bad target is a status in its feedback, never a broken stream. A
// new stream cancels the one before it. Stops and their clearing are logged with who and
// why.

#include <mutex>
#include <string>

#include "arm_sim/controller_stand_in.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "services/common/stream_limits.h"

namespace pnp::services {

// Who clears a stop, as logged and as the controller records it. Under an access policy it
// is the caller's authenticated principal, whatever name the request states (kept beside
// it in the log), so nobody can clear an emergency stop in another operator's name;
// without a policy (`principal` empty) it is the name the request states.
std::string clearing_operator(const std::string& principal, const std::string& stated);

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

class SimulatedSceneServiceImpl final : public robot::v1::SimulatedSceneService::Service {
 public:
  explicit SimulatedSceneServiceImpl(arm_sim::ControllerStandIn& arm) : arm_(arm) {}

  grpc::Status ResetScene(grpc::ServerContext* context, const robot::v1::ResetSceneRequest* request,
                          robot::v1::ResetSceneResponse* response) override;

 private:
  arm_sim::ControllerStandIn& arm_;
};

}  // namespace pnp::services
