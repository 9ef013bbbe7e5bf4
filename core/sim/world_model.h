#pragma once
// A compiled pick-and-place world: the immutable mjModel shared by every environment
// of the same robot, object and world profile, the ids the environment needs, and the
// home state (arm posed with the gripper at the profile's start pointing down, fingers
// open or closed as the profile has them) that every episode starts from.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_profile.h"

namespace pnp::sim {

inline constexpr int kArmJoints = 7;

struct WorldIds {
  int grip_site = -1;
  int object_body = -1;
  int object_qpos = -1;  // freejoint: 3 position + 4 quaternion
  int object_dof = -1;   // freejoint: 3 linear + 3 angular
  std::array<int, kArmJoints> arm_joints{};
  std::array<int, 2> finger_qpos{};
  std::array<int, 2> finger_dof{};
  std::array<int, 2> finger_actuator{};
  int arm_root_body = -1;  // first moving body of the arm: its subtree is arm + gripper
  int gripper_mocap = -1;  // mocap index of the body welded to the gripper
  int target_mocap = -1;   // mocap index of the goal marker
};

class WorldModel {
 public:
  // Builds the MJCF, compiles it and solves the home pose. Throws pnp::Error.
  static std::shared_ptr<const WorldModel> load(Robot robot, ObjectShape object,
                                                WorldProfile profile = WorldProfile::kPaper);

  const mjModel* mj() const { return model_.get(); }
  Robot robot() const { return robot_; }
  ObjectShape object() const { return object_; }
  WorldProfile profile() const { return profile_; }
  const WorldParameters& parameters() const { return world_parameters(profile_); }
  const ObjectSpec& object_spec() const { return object_spec_; }
  const WorldIds& ids() const { return ids_; }

  // Maximum travel of one finger (m); the opening between the pads is twice that.
  double finger_range_m() const { return finger_range_m_; }
  // The largest target a finger servo takes (m): the finger's range, or the profile's.
  double finger_ctrl_max_m() const { return finger_ctrl_max_m_; }
  // Orientation of the gripper's mocap target: local z (the approach axis) down.
  const Eigen::Vector4d& gripper_down_quat() const { return gripper_down_quat_; }

  // Home state: what reset() copies before placing the object.
  const std::vector<mjtNum>& home_qpos() const { return home_qpos_; }
  const std::vector<mjtNum>& home_qvel() const { return home_qvel_; }

 private:
  struct Passkey {};
  struct ModelDeleter {
    void operator()(mjModel* m) const { mj_deleteModel(m); }
  };

 public:
  WorldModel(Passkey, Robot robot, ObjectShape object, WorldProfile profile,
             std::unique_ptr<mjModel, ModelDeleter> model);

 private:
  void resolve_ids();
  void apply_finger_ctrl_range();
  void compute_home_state();

  Robot robot_;
  ObjectShape object_;
  WorldProfile profile_;
  ObjectSpec object_spec_;
  std::unique_ptr<mjModel, ModelDeleter> model_;
  WorldIds ids_;
  double finger_range_m_ = 0;
  double finger_ctrl_max_m_ = 0;
  Eigen::Vector4d gripper_down_quat_{0, 0, 1, 0};
  std::vector<mjtNum> home_qpos_;
  std::vector<mjtNum> home_qvel_;
};

}  // namespace pnp::sim
