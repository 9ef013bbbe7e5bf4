#pragma once
// The two arms the platform simulates. Both share the task frame in world_layout.h and
// differ only in their kinematic chain and gripper (see mjcf/fetch.xml, mjcf/panda.xml).

#include <array>
#include <string_view>

namespace pnp::sim {

enum class Robot { kFetch, kPanda };

inline constexpr std::array<Robot, 2> kAllRobots{Robot::kFetch, Robot::kPanda};

std::string_view robot_name(Robot robot);

// Parses "fetch" or "panda"; anything else is an INVALID_ARGUMENT naming `field`.
Robot parse_robot(std::string_view name, std::string_view field = "robot");

}  // namespace pnp::sim
