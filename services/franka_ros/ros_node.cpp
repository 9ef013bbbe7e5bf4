// Built as C++17 (ROS 1's headers): see ros_node.h.
#include "services/franka_ros/ros_node.h"

#include <ros/ros.h>

namespace pnp::services {

void init_ros_node(int& argc, char** argv, const std::string& node_name) {
  ros::init(argc, argv, node_name, ros::init_options::NoSigintHandler);
}

bool ros_master_reachable() {
  return ros::master::check();
}

void shutdown_ros_node() {
  ros::shutdown();
}

}  // namespace pnp::services
