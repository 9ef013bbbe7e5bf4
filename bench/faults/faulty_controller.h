#pragma once
// A fault-injecting proxy in front of a robot controller (pnp.robot.v1): every call is
// forwarded over gRPC to the real controller, and the fault armed in a FaultSwitch
// happens on the call it is planned for. What the gateway sees is what it would see
// from a real cell: a controller that stops answering (every call waits), a reading
// with a NaN, a zero quaternion or no object, a drive stream that breaks, an E-stop
// pressed by someone else (sent to the controller as a separate client would).

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>

#include "bench/faults/fault_switch.h"
#include "bench/faults/forward_call.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"

namespace pnp::faults {

class FaultyController final : public robot::v1::RobotControllerService::Service {
 public:
  FaultyController(const std::shared_ptr<grpc::Channel>& upstream, FaultSwitch& faults,
                   std::chrono::milliseconds stall);

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
  // A stalled controller answers nothing until the stall is over (or the caller leaves).
  void wait_out_stall(const grpc::ServerContext& context) const;
  void emergency_stop_from_the_cell();
  // A call forwarded once any stall is over.
  template <typename Request, typename Response>
  grpc::Status forward(
      const grpc::ServerContext& context,
      UnaryMethod<robot::v1::RobotControllerService::Stub, Request, Response> method,
      const Request& request, Response* response) {
    wait_out_stall(context);
    return forward_call(context, *upstream_, method, request, response);
  }

  std::unique_ptr<robot::v1::RobotControllerService::Stub> upstream_;
  FaultSwitch& faults_;
  std::chrono::milliseconds stall_;
};

// The scene service, forwarded as it is (the stand-in's episode resets).
class ForwardedScene final : public robot::v1::SimulatedSceneService::Service {
 public:
  explicit ForwardedScene(const std::shared_ptr<grpc::Channel>& upstream);
  grpc::Status ResetScene(grpc::ServerContext* context, const robot::v1::ResetSceneRequest* request,
                          robot::v1::ResetSceneResponse* response) override;

 private:
  std::unique_ptr<robot::v1::SimulatedSceneService::Stub> upstream_;
};

}  // namespace pnp::faults
