#include "services/franka_sim/franka_sim_scene_service.h"

#include "services/common/robot_convert.h"
#include "services/common/status.h"
#include "services/common/time_convert.h"

namespace pnp::services {

grpc::Status FrankaSimSceneService::ResetScene(grpc::ServerContext*,
                                               const robot::v1::ResetSceneRequest* request,
                                               robot::v1::ResetSceneResponse* response) {
  return guarded([&] {
    std::lock_guard lock(arm_mutex_);
    const arm_sim::Episode episode = arm_.reset(request->seed());
    const arm_sim::ArmState state = arm_.arm().state();
    auto& feedback = *response->mutable_state();
    to_proto(std::chrono::system_clock::now(), *feedback.mutable_stamp());
    feedback.set_frame_id(base_frame_id_);
    to_proto(state.tcp_base, *feedback.mutable_measured());
    to_proto(state.commanded_base, *feedback.mutable_commanded());
    feedback.set_gripper_width_m(state.finger_gap_m);
    to_proto(state.object_base, *feedback.mutable_object()->mutable_pose());
    feedback.set_mode(robot::v1::CONTROLLER_MODE_IDLE);
    feedback.set_status(robot::v1::CONTROLLER_STATUS_OK);
    to_proto(episode.goal_base, *response->mutable_goal());
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
