#pragma once
// pnp.robot.v1.SimulatedSceneService over the stand-in (arm_sim::ControllerStandIn): what
// only a simulated arm has, a seeded scene reset. Its controller is served by
// RobotControllerServiceImpl like any other.

#include "arm_sim/controller_stand_in.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "services/robot_controller/robot_controller_service.h"

namespace pnp::services {

class SimulatedSceneServiceImpl final : public robot::v1::SimulatedSceneService::Service {
 public:
  explicit SimulatedSceneServiceImpl(arm_sim::ControllerStandIn& arm) : arm_(arm) {}

  grpc::Status ResetScene(grpc::ServerContext* context, const robot::v1::ResetSceneRequest* request,
                          robot::v1::ResetSceneResponse* response) override;

 private:
  arm_sim::ControllerStandIn& arm_;
};

}  // namespace pnp::services
