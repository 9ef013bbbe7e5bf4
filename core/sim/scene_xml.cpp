#include "sim/scene_xml.h"

#include <fmt/format.h>

#include "common/error.h"
#include "sim/world_layout.h"
#include "sim_mjcf.h"

namespace pnp::sim {
namespace {

std::string_view robot_fragment(Robot robot) {
  switch (robot) {
    case Robot::kFetch:
      return mjcf::kfetchXml;
    case Robot::kPanda:
      return mjcf::kpandaXml;
  }
  throw_internal("robot_fragment: unknown Robot value");
}

std::string contact(const ContactParameters& c) {
  return fmt::format(R"(solref="{} {}" solimp="{} {} {}" margin="{}")", c.time_constant_s,
                     c.damping_ratio, c.impedance_min, c.impedance_max, c.impedance_width_m,
                     c.margin_m);
}

// The finger servo's force bound: none when the profile sets none (gym's).
std::string finger_force_range(const WorldParameters& p) {
  if (p.finger_force_limit_n <= 0) return "";
  return fmt::format(R"(forcerange="-{0} {0}")", p.finger_force_limit_n);
}

// Options and classes. Collision bits: the floor, the table and the object (contype 1,
// conaffinity 3) touch everything; the palm and the pads (1, 1) touch them; arm links
// (class "link") are visual in the paper world and (2, 0) in gym, so they touch the
// scenery but never each other or the gripper. Scenery geoms take the default contact,
// the robot's (link, collide, pad) the profile's robot contact.
std::string head(Robot robot, ObjectShape object, WorldProfile profile) {
  const WorldParameters& p = world_parameters(profile);
  const std::string robot_contact = contact(p.robot_contact);
  return fmt::format(R"(<mujoco model="pnp_{}_{}_{}">
  <compiler angle="radian" autolimits="true" inertiafromgeom="true"/>
  <option timestep="{}" iterations="{}" tolerance="1e-8" cone="pyramidal"/>
  <size njmax="400" nconmax="80"/>
  <default>
    <geom contype="0" conaffinity="0" friction="1 0.005 0.0001" {}/>
    <joint damping="0" armature="0"/>
    <default class="visual"><geom contype="0" conaffinity="0" group="1" rgba="0.7 0.7 0.75 1"/></default>
    <default class="link"><geom contype="{}" conaffinity="0" condim="3" group="1" rgba="0.7 0.7 0.75 1" {}/></default>
    <default class="collide"><geom contype="1" conaffinity="1" condim="3" {}/></default>
    <default class="scenery"><geom contype="1" conaffinity="3" condim="3"/></default>
    <default class="pad"><geom type="box" contype="1" conaffinity="1" condim="{}" mass="{}"
                               friction="{} {} {}" rgba="0.2 0.2 0.2 1" {}/></default>
    <default class="arm"><joint type="hinge" axis="0 0 1" damping="{}" armature="{}"/></default>
    <default class="finger">
      <joint type="slide" damping="{}" armature="{}"/>
      <position kp="{}" {}/>
    </default>
  </default>
)",
                     robot_name(robot), object_name(object), world_profile_name(profile),
                     layout::kPhysicsTimestep_s, p.solver_iterations, contact(p.scenery_contact),
                     p.arm_links_collide ? 2 : 0, robot_contact, robot_contact, p.pad_condim,
                     p.finger_mass_kg, p.pad_friction[0], p.pad_friction[1], p.pad_friction[2],
                     robot_contact, p.arm_damping, p.arm_armature, p.finger_damping,
                     p.finger_armature, p.finger_kp, finger_force_range(p));
}

std::string object_geom(const ObjectSpec& spec, const WorldParameters& p) {
  if (spec.is_cylinder) {
    return fmt::format(R"(type="cylinder" size="{} {}" {})", spec.half_width_m, spec.half_height_m,
                       contact(p.cylinder_contact));
  }
  return fmt::format(R"(type="box" size="{0} {0} {1}")", spec.half_width_m, spec.half_height_m);
}

std::string scene_bodies(ObjectShape object, WorldProfile profile) {
  const ObjectSpec spec = profiled_object_spec(object, profile);
  const Eigen::Vector3d start = world_parameters(profile).gripper_start();
  return fmt::format(
      R"(  <worldbody>
    <light pos="1.3 0.75 2.5" dir="0 0 -1" directional="true"/>
    <geom name="floor" class="scenery" type="plane" size="3 3 0.1" rgba="0.5 0.55 0.6 1"/>
    <body name="table" pos="{} {} {}">
      <geom name="table" class="scenery" type="box" size="{} {} {}" rgba="0.6 0.45 0.3 1"/>
    </body>
    <body name="object" pos="{} {} {}">
      <freejoint name="object"/>
      <geom name="object" class="scenery" {} mass="{}" condim="{}" rgba="0.2 0.4 0.9 1"/>
    </body>
    <body name="target" mocap="true" pos="{} {} {}">
      <site name="target" type="sphere" size="0.02" rgba="0.9 0.1 0.1 0.4"/>
    </body>
    <body name="gripper_target" mocap="true" pos="{} {} {}" quat="0 0 1 0"/>
  </worldbody>
  <equality>
    <weld name="gripper_follows_target" body1="gripper_target" body2="gripper"
          relpose="0 0 0 1 0 0 0" solref="0.02 1" solimp="0.9 0.95 0.001"/>
  </equality>
)",
      layout::kTableCenter_x, layout::kTableCenter_y, layout::kTableTop_z / 2, layout::kTableHalfX,
      layout::kTableHalfY, layout::kTableTop_z / 2, start.x(), start.y() + 0.12,
      layout::kTableTop_z + spec.half_height_m, object_geom(spec, world_parameters(profile)),
      spec.mass_kg, world_parameters(profile).object_condim, start.x(), start.y(),
      layout::kTableTop_z + spec.half_height_m, start.x(), start.y(), start.z());
}

// The robot fragment is a complete <mujoco> document; its children are spliced in.
std::string_view fragment_body(std::string_view fragment) {
  const auto open = fragment.find("<mujoco>");
  const auto close = fragment.rfind("</mujoco>");
  if (open == std::string_view::npos || close == std::string_view::npos || close < open) {
    throw_internal("robot MJCF fragment is not wrapped in <mujoco>...</mujoco>");
  }
  const auto begin = open + std::string_view("<mujoco>").size();
  return fragment.substr(begin, close - begin);
}

}  // namespace

ObjectSpec profiled_object_spec(ObjectShape object, WorldProfile profile) {
  ObjectSpec spec = object_spec(object);
  spec.mass_kg *= world_parameters(profile).object_mass_scale;
  return spec;
}

std::string scene_xml(Robot robot, ObjectShape object, WorldProfile profile) {
  std::string xml = head(robot, object, profile);
  xml += scene_bodies(object, profile);
  xml += fragment_body(robot_fragment(robot));
  xml += "</mujoco>\n";
  return xml;
}

}  // namespace pnp::sim
