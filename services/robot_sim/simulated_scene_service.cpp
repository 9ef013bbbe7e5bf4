#include "services/robot_sim/simulated_scene_service.h"

#include "services/common/robot_convert.h"
#include "services/common/status.h"
#include "services/robot_controller/feedback_convert.h"

namespace pnp::services {

grpc::Status SimulatedSceneServiceImpl::ResetScene(grpc::ServerContext*,
                                                   const robot::v1::ResetSceneRequest* request,
                                                   robot::v1::ResetSceneResponse* response) {
  return guarded([&] {
    require_lease_id(request->lease_id());
    const auto reset = arm_.reset_scene(request->lease_id(), request->seed());
    to_proto(reset.report, arm_.base_frame_id(), *response->mutable_state());
    to_proto(reset.goal_base, *response->mutable_goal());
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
