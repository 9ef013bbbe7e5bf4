#pragma once
// This process as a ROS 1 node, for the C++20 mains of pnp-franka-bridge and
// pnp-franka-sim (ROS's own headers are C++17 only: proto/ros/README.md).

#include <string>

namespace pnp::services {

// ros::init (before any publisher or subscriber). No SIGINT handler is installed: the
// process's own shutdown handles its signals. Reads ROS_MASTER_URI as any node does.
void init_ros_node(int& argc, char** argv, const std::string& node_name);
bool ros_master_reachable();  // the master answers
void shutdown_ros_node();

}  // namespace pnp::services
