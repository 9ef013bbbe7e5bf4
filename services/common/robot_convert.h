#pragma once
// pnp.robot.v1 poses, positions and timestamps <-> core types, read the same way by
// pnp-robot-sim and pnp-robot-gateway.

#include <Eigen/Core>
#include <chrono>

#include "geometry/pose.h"
#include "pnp/robot/v1/robot_controller.pb.h"

namespace pnp::services {

void to_proto(const geometry::Pose& pose, robot::v1::Pose& out);
// Not validated: the receiver checks finiteness and norms where it acts on them.
geometry::Pose from_proto(const robot::v1::Pose& pose);
Eigen::Vector3d from_proto(const robot::v1::Position& position);
void to_proto(const Eigen::Vector3d& position, robot::v1::Position& out);

void to_proto(std::chrono::system_clock::time_point time, google::protobuf::Timestamp& out);

}  // namespace pnp::services
