#include "services/common/robot_convert.h"

namespace pnp::services {

void to_proto(const Eigen::Vector3d& position, robot::v1::Position& out) {
  out.set_x_m(position.x());
  out.set_y_m(position.y());
  out.set_z_m(position.z());
}

Eigen::Vector3d from_proto(const robot::v1::Position& position) {
  return {position.x_m(), position.y_m(), position.z_m()};
}

void to_proto(const geometry::Pose& pose, robot::v1::Pose& out) {
  to_proto(pose.position_m, *out.mutable_position());
  auto& q = *out.mutable_orientation();
  q.set_w(pose.orientation.w());
  q.set_x(pose.orientation.x());
  q.set_y(pose.orientation.y());
  q.set_z(pose.orientation.z());
}

geometry::Pose from_proto(const robot::v1::Pose& pose) {
  const auto& q = pose.orientation();
  return {from_proto(pose.position()), Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z())};
}

}  // namespace pnp::services
