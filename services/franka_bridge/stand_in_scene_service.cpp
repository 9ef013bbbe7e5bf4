#include "services/franka_bridge/stand_in_scene_service.h"

#include <grpcpp/grpcpp.h>

#include <chrono>

#include "common/error.h"
#include "services/common/status.h"
#include "services/robot_controller/feedback_convert.h"
#include "services/robot_controller/robot_controller_service.h"

namespace pnp::services {

StandInSceneService::StandInSceneService(robot::FrankaController& arm,
                                         const std::string& stand_in_address)
    : arm_(arm),
      address_(stand_in_address),
      stand_in_(robot::v1::SimulatedSceneService::NewStub(
          grpc::CreateChannel(stand_in_address, grpc::InsecureChannelCredentials()))) {}

grpc::Status StandInSceneService::ResetScene(grpc::ServerContext*,
                                             const robot::v1::ResetSceneRequest* request,
                                             robot::v1::ResetSceneResponse* response) {
  return guarded([&] {
    require_lease_id(request->lease_id());
    auto [remote, report] = arm_.reset_scene(request->lease_id(), [&] {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
      robot::v1::ResetSceneResponse answer;
      const grpc::Status status = stand_in_->ResetScene(&context, *request, &answer);
      if (!status.ok()) {
        throw Error(ErrorCode::kUnavailable,
                    "the stand-in's scene service (" + address_ + "): " + status.error_message());
      }
      return answer;
    });
    *response->mutable_goal() = remote.goal();
    to_proto(report, arm_.base_frame_id(), *response->mutable_state());
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
