#include "sim/robot.h"

#include <string>

#include "common/enum_names.h"
#include "common/error.h"

namespace pnp::sim {

std::string_view robot_name(Robot robot) {
  switch (robot) {
    case Robot::kFetch:
      return "fetch";
    case Robot::kPanda:
      return "panda";
  }
  throw_internal("robot_name: unknown Robot value");
}

Robot parse_robot(std::string_view name, std::string_view field) {
  return parse_enum<Robot>(name, kAllRobots, &robot_name, field);
}

}  // namespace pnp::sim
