#include "sim/world_model.h"

#include <Eigen/Geometry>
#include <cstring>
#include <string>

#include "common/error.h"
#include "sim/gravity_compensation.h"
#include "sim/inverse_kinematics.h"
#include "sim/mujoco_data.h"
#include "sim/scene_xml.h"

namespace pnp::sim {
namespace {

// MuJoCo 2.2 has no mj_addBufferVFS: an in-memory file is an empty VFS file filled by
// hand. The mjVFS is ~2 MB, so it lives on the heap.
class ScopedVfs {
 public:
  ScopedVfs() { mj_defaultVFS(vfs_.get()); }
  ~ScopedVfs() { mj_deleteVFS(vfs_.get()); }
  ScopedVfs(const ScopedVfs&) = delete;
  ScopedVfs& operator=(const ScopedVfs&) = delete;
  mjVFS* get() { return vfs_.get(); }

 private:
  std::unique_ptr<mjVFS> vfs_ = std::make_unique<mjVFS>();
};

mjModel* compile_mjcf(const std::string& xml) {
  ScopedVfs vfs;
  const char* kFileName = "scene.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kFileName, static_cast<int>(xml.size())) != 0) {
    throw_internal("could not allocate the in-memory MJCF file");
  }
  const int index = mj_findFileVFS(vfs.get(), kFileName);
  std::memcpy(vfs.get()->filedata[index], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* model = mj_loadXML(kFileName, vfs.get(), error, sizeof(error));
  if (!model) throw_internal(std::string("MJCF did not compile: ") + error);
  return model;
}

int require_id(const mjModel* m, mjtObj type, const char* name) {
  const int id = mj_name2id(m, type, name);
  if (id < 0) throw_internal(std::string("MJCF is missing required element \"") + name + "\"");
  return id;
}

// Starting guesses for the home-pose IK (elbow up, wrist over the table).
std::array<double, kArmJoints> nominal_posture(Robot robot) {
  switch (robot) {
    case Robot::kFetch:
      return {0.0, 0.3, 0.0, 1.0, 0.0, 0.27, 0.0};
    case Robot::kPanda:
      return {0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785};
  }
  throw_internal("nominal_posture: unknown Robot value");
}

// The weld holds the gripper body at a pose relative to its mocap target; offsetting it
// by the TCP site's position (in the gripper frame) makes the mocap target the TCP. The
// offset is read from the compiled model, so each robot's own TCP is used.
void weld_mocap_to_tcp(mjModel* m, int grip_site) {
  const int weld = require_id(m, mjOBJ_EQUALITY, "gripper_follows_target");
  if (m->site_bodyid[grip_site] != m->eq_obj2id[weld]) {
    throw_internal("site \"grip\" must belong to the body welded to the gripper target");
  }
  mjtNum* relpose = m->eq_data + mjNEQDATA * weld + 3;  // after the 3-value anchor
  for (int k = 0; k < 3; ++k) relpose[k] = -m->site_pos[3 * grip_site + k];
}

}  // namespace

std::shared_ptr<const WorldModel> WorldModel::load(Robot robot, ObjectShape object,
                                                   WorldProfile profile) {
  route_mujoco_messages();
  std::unique_ptr<mjModel, ModelDeleter> model(compile_mjcf(scene_xml(robot, object, profile)));
  auto world = std::make_shared<WorldModel>(Passkey{}, robot, object, profile, std::move(model));
  world->resolve_ids();
  world->apply_finger_ctrl_range();
  world->compute_home_state();
  return world;
}

WorldModel::WorldModel(Passkey /*only load() constructs*/, Robot robot, ObjectShape object,
                       WorldProfile profile, std::unique_ptr<mjModel, ModelDeleter> model)
    : robot_(robot),
      object_(object),
      profile_(profile),
      object_spec_(profiled_object_spec(object, profile)),
      model_(std::move(model)) {}

void WorldModel::resolve_ids() {
  const mjModel* m = model_.get();
  ids_.grip_site = require_id(m, mjOBJ_SITE, "grip");
  ids_.object_body = require_id(m, mjOBJ_BODY, "object");
  const int object_joint = require_id(m, mjOBJ_JOINT, "object");
  ids_.object_qpos = m->jnt_qposadr[object_joint];
  ids_.object_dof = m->jnt_dofadr[object_joint];
  const char* finger_names[2] = {"finger_left", "finger_right"};
  for (int f = 0; f < 2; ++f) {
    const int joint = require_id(m, mjOBJ_JOINT, finger_names[f]);
    ids_.finger_qpos[static_cast<std::size_t>(f)] = m->jnt_qposadr[joint];
    ids_.finger_dof[static_cast<std::size_t>(f)] = m->jnt_dofadr[joint];
    ids_.finger_actuator[static_cast<std::size_t>(f)] =
        require_id(m, mjOBJ_ACTUATOR, finger_names[f]);
    finger_range_m_ = m->jnt_range[2 * joint + 1];
  }
  // The arm joints are the model's hinges, in kinematic-tree order.
  int arm = 0;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_HINGE) continue;
    if (arm == kArmJoints) throw_internal("robot MJCF has more than 7 hinge joints");
    ids_.arm_joints[static_cast<std::size_t>(arm++)] = j;
  }
  if (arm != kArmJoints) throw_internal("robot MJCF has fewer than 7 hinge joints");
  ids_.arm_root_body = m->jnt_bodyid[ids_.arm_joints[0]];
  ids_.gripper_mocap = m->body_mocapid[require_id(m, mjOBJ_BODY, "gripper_target")];
  weld_mocap_to_tcp(model_.get(), ids_.grip_site);
  ids_.target_mocap = m->body_mocapid[require_id(m, mjOBJ_BODY, "target")];
}

// The fragments' finger servos take targets within the joint's range; a profile may widen
// that (gym's 0.2 m), which the servo then drives against the joint's stop.
void WorldModel::apply_finger_ctrl_range() {
  const double ctrl_max = parameters().finger_ctrl_max_m;
  for (int actuator : ids_.finger_actuator) {
    if (ctrl_max > 0) model_->actuator_ctrlrange[2 * actuator + 1] = ctrl_max;
  }
  finger_ctrl_max_m_ = model_->actuator_ctrlrange[2 * ids_.finger_actuator[0] + 1];
}

void WorldModel::compute_home_state() {
  const mjModel* m = model_.get();
  DataPtr data = make_data(m);
  mjData* d = data.get();

  // Gripper pointing down: rotation by pi about world y (local z -> -z, fingers along y).
  const Eigen::Quaterniond down(gripper_down_quat_(0), gripper_down_quat_(1), gripper_down_quat_(2),
                                gripper_down_quat_(3));
  const auto nominal = nominal_posture(robot_);
  for (int j = 0; j < kArmJoints; ++j) {
    d->qpos[m->jnt_qposadr[ids_.arm_joints[static_cast<std::size_t>(j)]]] =
        nominal[static_cast<std::size_t>(j)];
  }
  const Eigen::Vector3d start = parameters().gripper_start();
  const IkResult ik = solve_site_ik(m, d, ids_.grip_site, ids_.arm_joints,
                                    {start, down.toRotationMatrix()}, nominal);
  if (!ik.converged) {
    throw_internal("home pose IK did not converge for robot " + std::string(robot_name(robot_)) +
                   ": position error " + std::to_string(ik.position_error_m) + " m");
  }

  // Let the weld, gravity and the fingers settle for 0.5 s so that episodes start from
  // rest rather than from a state the constraints will immediately correct.
  const double fingers = parameters().fingers_open_at_reset ? finger_range_m_ : 0.0;
  for (int f = 0; f < 2; ++f) {
    d->qpos[ids_.finger_qpos[static_cast<std::size_t>(f)]] = fingers;
    d->ctrl[ids_.finger_actuator[static_cast<std::size_t>(f)]] = fingers;
  }
  for (int k = 0; k < 3; ++k) d->mocap_pos[3 * ids_.gripper_mocap + k] = start(k);
  for (int k = 0; k < 4; ++k) d->mocap_quat[4 * ids_.gripper_mocap + k] = gripper_down_quat_(k);
  mju_zero(d->qvel, m->nv);
  GravityCompensation compensation(m, ids_.arm_root_body);
  for (int i = 0; i < 250; ++i) {
    if (parameters().gravity_compensation) compensation.apply(m, d);
    mj_step(m, d);
  }
  home_qpos_.assign(d->qpos, d->qpos + m->nq);
  home_qvel_.assign(d->qvel, d->qvel + m->nv);
}

}  // namespace pnp::sim
