#include "sim/actuation.h"

#include <string>

#include "common/enum_names.h"
#include "common/error.h"
#include "sim/world_layout.h"

namespace pnp::sim {

std::string_view actuation_name(Actuation actuation) {
  switch (actuation) {
    case Actuation::kMocap:
      return "mocap";
    case Actuation::kArm:
      return "arm";
  }
  throw_internal("actuation_name: unknown Actuation value");
}

Actuation parse_actuation(std::string_view name, std::string_view field) {
  return parse_enum<Actuation>(name, kAllActuations, &actuation_name, field);
}

Actuation default_actuation(Robot robot) {
  switch (robot) {
    case Robot::kFetch:  // gym's control: gym is the benchmark
      return Actuation::kMocap;
    case Robot::kPanda:          // until an arm-trained hierarchy holds its results on the arm
      return Actuation::kMocap;  // (docs/RESULTS.md, "Trained through the arm's controller")
  }
  throw_internal("default_actuation: unknown Robot value");
}

int episode_steps(Actuation actuation) {
  switch (actuation) {
    case Actuation::kMocap:
      return layout::kEpisodeSteps;
    case Actuation::kArm:
      return layout::kArmEpisodeSteps;
  }
  throw_internal("episode_steps: unknown Actuation value");
}

void require_supported(Robot robot, Actuation actuation, std::string_view field) {
  if (actuation == Actuation::kArm && robot != Robot::kPanda) {
    throw_invalid_argument(field,
                           "mocap for robot " + std::string(robot_name(robot)) +
                               " (only the Panda has an arm controller)",
                           "\"arm\"");
  }
}

}  // namespace pnp::sim
