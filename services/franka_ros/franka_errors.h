#pragma once
// franka_msgs/Errors by name: the one table of its 41 flags that the bridge reads and the
// stand-in Franka sets. ROS 1 headers: include from C++17 sources only
// (proto/ros/README.md).

#include <string>
#include <vector>

#include "franka_msgs/Errors.h"

namespace pnp::services {

// The names of the flags that are set, in the message's order.
std::vector<std::string> set_error_names(const franka_msgs::Errors& errors);
// Sets the flag called `name`; false (nothing set) for a name franka_msgs does not have.
bool set_error_flag(franka_msgs::Errors& errors, const std::string& name);

}  // namespace pnp::services
