#pragma once
// World profiles: which version of the pick-and-place world an environment simulates.
//
//   paper  the authors' patched FetchPickAndPlace: goals at most 0.15 m above the table,
//          a light block, grippy pads, arm links that never touch anything, a mocap
//          target that accumulates actions inside a table-sized box, fingers open at reset.
//   gym    FetchPickAndPlace-v1 parameter for parameter where this simulation allows:
//          goals up to 0.45 m, a 2 kg block (condim 3), gym's pad friction, arm links
//          that collide with the table and the object, the target reset to the gripper
//          before each action with no clamp, fingers closed at reset, ctrl = q + a.
//
// Every number that differs between the profiles is a field here, defined once per
// profile; docs/SIMULATION.md tabulates both beside gym and panda-gym with sources.

#include <Eigen/Core>
#include <array>
#include <string_view>

namespace pnp::sim {

enum class WorldProfile { kPaper, kGym };

inline constexpr std::array<WorldProfile, 2> kAllWorldProfiles{WorldProfile::kPaper,
                                                               WorldProfile::kGym};

std::string_view world_profile_name(WorldProfile profile);
// The world a tool, service or request uses unless told otherwise: gym's, the benchmark
// users know. (Records from before world profiles were all made in the paper world.)
inline constexpr WorldProfile kDefaultWorldProfile = WorldProfile::kGym;

// Parses "paper" or "gym"; anything else is an INVALID_ARGUMENT naming `field`.
WorldProfile parse_world_profile(std::string_view name, std::string_view field = "world");

// How an action's xyz moves the gripper's mocap target.
enum class MocapControl {
  kAccumulateClamped,  // target += 0.05 a, kept inside layout::kWorkspaceMin/Max
  kFromGripper,        // target = the gripper's current TCP + 0.05 a (gym's mocap reset)
};

// A geom class's contact softness (MuJoCo's solref and solimp) and margin.
struct ContactParameters {
  double time_constant_s = 0.02;  // solref: MuJoCo's defaults
  double damping_ratio = 1;
  double impedance_min = 0.9;  // solimp
  double impedance_max = 0.95;
  double impedance_width_m = 0.001;
  double margin_m = 0;
};

struct WorldParameters {
  // Scene sampling around the gripper's start xy.
  double gripper_start_above_table_m = 0;  // the TCP's start height over the table top
  double object_range_m = 0;               // object xy = start xy + U(-r, r)^2 ...
  double object_min_distance_m = 0;        // ... at least this far from the start xy
  double goal_range_m = 0;                 // goal xy = start xy + U(-r, r)^2
  double goal_air_probability = 0;         // the goal is raised with this probability ...
  double goal_max_height_m = 0;            // ... by U(0, h) above the object's resting height

  // Every object's mass is object_shape.h's times this. Gym's block weighs 2 kg, 20 times
  // ours; the small block and the cylinder scale with it, since a 20 g cylinder squeezed
  // by gym's 200 N grip pops out of the hand (measured: every scripted episode faulted).
  double object_mass_scale = 1;
  int object_condim = 0;  // 3: sliding friction only; 4: plus torsional

  // Contact and control.
  ContactParameters robot_contact;    // every robot geom: links, palm, pads
  ContactParameters scenery_contact;  // floor, table and object
  // The cylinder is not gym's: a 2 cm cylinder held between the pads slips and turns out
  // of the hand with gym's soft contacts (scripted Panda 0.54 of 1000 with every gym value);
  // it keeps the stiff contact it was grasped with before the gym profile had gym's.
  ContactParameters cylinder_contact;
  int solver_iterations = 0;  // MuJoCo's constraint solver, per step
  // The arm's joints: damping (N m s/rad) and armature (kg m^2), every hinge alike.
  double arm_damping = 0;
  double arm_armature = 0;
  // Joint torques -J_com^T M g cancel the arm's weight, as a real arm's controller does;
  // without them only the mocap weld holds the arm up.
  bool gravity_compensation = false;
  std::array<double, 3> pad_friction{};  // sliding, torsional, rolling
  int pad_condim = 0;
  bool arm_links_collide = false;  // with the table and the object (never with each other)
  MocapControl mocap = MocapControl::kAccumulateClamped;
  // Finger command: ctrl = q + action(3) * scale, in metres, clamped to the finger's
  // range. The paper world scales by the finger's range (proportional); gym adds the
  // raw action (1 m per unit: effectively open or close at any sizeable action).
  bool finger_action_in_metres = false;
  // The finger position servo: gain (N/m) and force limit (N, 0: none) per finger. Gym's
  // Fetch squeezes with kp 30000 and no limit; a 2 kg block slips out of a 40 N grasp when
  // it is lifted.
  double finger_kp = 0;
  double finger_force_limit_n = 0;
  // The finger slide joints' damping (N s/m) and armature (kg). Gym's damping 1000 makes
  // the fingers close over a few steps instead of slamming shut in one; gym's armature
  // 100 we do not copy: 100 kg of finger inertia arriving at 0.2 m/s drove the pads 3 mm
  // into a cylinder and flung it out (measured: 26% scripted success on Fetch, 0 faults
  // and 100% with armature 1).
  double finger_damping = 0;
  double finger_armature = 0;
  double finger_mass_kg = 0;  // each finger's moving body (its pad)
  // The finger servo's largest target (m): 0 means the joint's own range. gym's 0.2 lets
  // an opening finger be driven far past its 5 cm stop, so it opens fast and hard.
  double finger_ctrl_max_m = 0;
  bool fingers_open_at_reset = true;

  Eigen::Vector3d gripper_start() const;  // the TCP's start, world frame
};

const WorldParameters& world_parameters(WorldProfile profile);

}  // namespace pnp::sim
