#pragma once
// Writes the MJCF of a pick-and-place world: the scene parts that every robot shares
// (physics options, classes, floor, table, object, goal marker, and the mocap target
// welded to the robot's "gripper" body) generated from world_layout.h and the object's
// spec, followed by the robot's own fragment (mjcf/<robot>.xml, embedded at build time).

#include <string>

#include "sim/object_shape.h"
#include "sim/robot.h"

namespace pnp::sim {

std::string scene_xml(Robot robot, ObjectShape object);

}  // namespace pnp::sim
