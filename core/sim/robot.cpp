#include "sim/robot.h"

#include <string>

#include "common/error.h"

namespace pnp::sim {

std::string_view robot_name(Robot robot) {
  switch (robot) {
    case Robot::kFetch: return "fetch";
    case Robot::kPanda: return "panda";
  }
  throw_internal("robot_name: unknown Robot value");
}

Robot parse_robot(std::string_view name, std::string_view field) {
  for (Robot robot : kAllRobots) {
    if (robot_name(robot) == name) return robot;
  }
  throw_invalid_argument(field, "one of fetch, panda", "\"" + std::string(name) + "\"");
}

}  // namespace pnp::sim
