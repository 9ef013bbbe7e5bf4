#include "sim/world_profile.h"

#include "common/enum_names.h"
#include "common/error.h"
#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

// The authors' patched FetchPickAndPlace (repository lmarza/DRL-for-Pick-and-Place-Task-
// subtasks, gymModified/): goal heights U(0, 0.15); the rest is this project's world as
// it was before the gym profile (light block, grippy pads, visual-only arm links).
constexpr ContactParameters kStiffContact{0.004, 1, 0.95, 0.99, 0.001, 0};

constexpr WorldParameters kPaper{
    .gripper_start_above_table_m = layout::kPaperGripperStartHeight,
    .object_range_m = 0.15,
    .object_min_distance_m = 0.10,
    .goal_range_m = 0.15,
    .goal_air_probability = 0.5,
    .goal_max_height_m = 0.15,
    .object_mass_scale = 1,
    .object_condim = 4,
    // Stiff contacts for light objects: a 4 ms time constant (2 x dt), impedance 0.95-0.99;
    // the pads sink 1 mm into a 20 g cylinder held with 10 N, not 5 mm as with MuJoCo's.
    .robot_contact = kStiffContact,
    .scenery_contact = kStiffContact,
    .cylinder_contact = kStiffContact,
    .solver_iterations = 30,
    .arm_damping = 4,
    .arm_armature = 0.05,
    .gravity_compensation = true,
    .pad_friction = {1.5, 0.01, 0.0001},
    .pad_condim = 4,
    .arm_links_collide = false,
    .mocap = MocapControl::kAccumulateClamped,
    .finger_action_in_metres = false,
    .finger_kp = 1000,
    .finger_force_limit_n = 40,
    .finger_damping = 20,
    .finger_armature = 0.01,
    .finger_mass_kg = 0.08,
    .finger_ctrl_max_m = 0,
    .fingers_open_at_reset = true,
};

// FetchPickAndPlace-v1 (openai/gym, gym/envs/robotics/): fetch_env.py (_sample_goal,
// _reset_sim, _set_action, _env_setup), utils.py (mocap_set_action, ctrl_set_action),
// assets/fetch/{pick_and_place,robot}.xml. The start height: gym's grip site starts
// ~0.11 m above the resting block's centre (0.025 m half height).
constexpr WorldParameters kGym{
    .gripper_start_above_table_m = 0.135,
    .object_range_m = 0.15,
    .object_min_distance_m = 0.10,
    .goal_range_m = 0.15,
    .goal_air_probability = 0.5,
    .goal_max_height_m = 0.45,
    .object_mass_scale = 20,  // the block: 2 kg
    .object_condim = 3,
    // The robot's geoms as gym's class robot0:fetch (shared.xml); the table, floor and
    // object keep MuJoCo's defaults, as in pick_and_place.xml; MuJoCo's default solver.
    .robot_contact = {0.01, 1, 0.99, 0.99, 0.01, 0.001},
    .scenery_contact = {},
    .cylinder_contact = kStiffContact,
    .solver_iterations = 100,
    // Class robot0:fetch's joints; no gravity compensation: the mocap weld holds the arm.
    .arm_damping = 50,
    .arm_armature = 1,
    .gravity_compensation = false,
    .pad_friction = {1.0, 0.05, 0.01},
    .pad_condim = 4,
    .arm_links_collide = true,
    .mocap = MocapControl::kFromGripper,
    .finger_action_in_metres = true,
    // Class robot0:fetchGripper and the finger links of robot.xml, the actuators of
    // pick_and_place.xml: 4 kg fingers, damping 1000, kp 30000, targets up to 0.2 m. Two
    // departures, for our thinner objects (gym's block grasps with gym's values too): a
    // 200 N force limit where gym has none, and armature 1 where gym has 100, which drove
    // the pads 3 mm into the cylinder (scripted, every other gym value: Fetch 0.017 with
    // 103 faults, Panda 0.539 of 1000; docs/SIMULATION.md).
    .finger_kp = 30000,
    .finger_force_limit_n = 200,
    .finger_damping = 1000,
    .finger_armature = 1,
    .finger_mass_kg = 4,
    .finger_ctrl_max_m = 0.2,
    .fingers_open_at_reset = false,
};

}  // namespace

std::string_view world_profile_name(WorldProfile profile) {
  switch (profile) {
    case WorldProfile::kPaper:
      return "paper";
    case WorldProfile::kGym:
      return "gym";
  }
  throw_internal("world_profile_name: unknown WorldProfile value");
}

WorldProfile parse_world_profile(std::string_view name, std::string_view field) {
  return parse_enum<WorldProfile>(name, kAllWorldProfiles, &world_profile_name, field);
}

Eigen::Vector3d WorldParameters::gripper_start() const {
  return {layout::kGripperStart_x, layout::kGripperStart_y,
          layout::kTableTop_z + gripper_start_above_table_m};
}

const WorldParameters& world_parameters(WorldProfile profile) {
  switch (profile) {
    case WorldProfile::kPaper:
      return kPaper;
    case WorldProfile::kGym:
      return kGym;
  }
  throw_internal("world_parameters: unknown WorldProfile value");
}

}  // namespace pnp::sim
