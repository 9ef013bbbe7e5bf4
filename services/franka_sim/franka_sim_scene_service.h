#pragma once
// pnp.robot.v1.SimulatedSceneService over the stand-in Franka: a seeded episode's scene
// (home posture, object, goal), as pnp-robot-sim's. The stand-in's own control, never a
// real arm's: pnp-franka-bridge forwards a gateway's ResetScene here when started with
// --stand-in-scene, after checking the gateway's lease itself.

#include <mutex>

#include "arm_sim/franka_stand_in.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"

namespace pnp::services {

class FrankaSimSceneService final : public robot::v1::SimulatedSceneService::Service {
 public:
  // `arm` is used under `arm_mutex`; both must outlive the service.
  FrankaSimSceneService(arm_sim::FrankaStandIn& arm, std::mutex& arm_mutex,
                        std::string base_frame_id)
      : arm_(arm), arm_mutex_(arm_mutex), base_frame_id_(std::move(base_frame_id)) {}

  grpc::Status ResetScene(grpc::ServerContext* context, const robot::v1::ResetSceneRequest* request,
                          robot::v1::ResetSceneResponse* response) override;

 private:
  arm_sim::FrankaStandIn& arm_;
  std::mutex& arm_mutex_;
  const std::string base_frame_id_;
};

}  // namespace pnp::services
