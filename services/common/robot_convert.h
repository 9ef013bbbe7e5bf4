#pragma once
// pnp.robot.v1 poses and positions <-> core types, read the same way by
// pnp-robot-sim and pnp-robot-gateway.

#include <Eigen/Core>
#include <chrono>

#include "geometry/pose.h"
#include "pnp/robot/v1/robot_controller.pb.h"
#include "services/common/time_convert.h"  // timestamps in these messages

namespace pnp::services {

void to_proto(const geometry::Pose& pose, robot::v1::Pose& out);
// Not validated: the receiver checks finiteness and norms where it acts on them.
geometry::Pose from_proto(const robot::v1::Pose& pose);
Eigen::Vector3d from_proto(const robot::v1::Position& position);
void to_proto(const Eigen::Vector3d& position, robot::v1::Position& out);

}  // namespace pnp::services
