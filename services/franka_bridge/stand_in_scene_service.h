#pragma once
// pnp-franka-bridge --stand-in-scene ADDRESS: SimulatedSceneService for a gateway driving
// the stand-in Franka, so that gateway episodes through the bridge start where they start
// on pnp-robot-sim. The gateway's lease is checked here; the reset itself is forwarded to
// pnp-franka-sim's scene service; the bridge then holds where the arm was put. A real arm
// has no such service: the flag is for the stand-in only.

#include <memory>
#include <string>

#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "robot/franka_controller.h"

namespace pnp::services {

class StandInSceneService final : public robot::v1::SimulatedSceneService::Service {
 public:
  StandInSceneService(robot::FrankaController& arm, const std::string& stand_in_address);

  grpc::Status ResetScene(grpc::ServerContext* context, const robot::v1::ResetSceneRequest* request,
                          robot::v1::ResetSceneResponse* response) override;

 private:
  robot::FrankaController& arm_;
  std::string address_;
  std::unique_ptr<robot::v1::SimulatedSceneService::Stub> stand_in_;
};

}  // namespace pnp::services
