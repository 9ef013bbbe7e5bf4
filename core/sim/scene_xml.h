#pragma once
// Writes the MJCF of a pick-and-place world: the scene parts that every robot shares
// (physics options, classes, floor, table, object, goal marker, and the mocap target
// welded to the robot's "gripper" body) generated from world_layout.h and the object's
// spec, followed by the robot's own fragment (mjcf/<robot>.xml, embedded at build time).
// The world profile sets the object's mass and contact, the pads' friction and whether
// the arm's links (class "link" in the fragments) collide.

#include <string>

#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_profile.h"

namespace pnp::sim {

std::string scene_xml(Robot robot, ObjectShape object, WorldProfile profile);

// The object as the profile has it: object_shape.h's spec with the profile's block mass.
ObjectSpec profiled_object_spec(ObjectShape object, WorldProfile profile);

}  // namespace pnp::sim
