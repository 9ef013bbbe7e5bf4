#include "sim/pick_place_env.h"

#include <algorithm>

#include "sim/physics_fault.h"
#include "sim/step_rules.h"
#include "sim/task_sampler.h"
#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

Eigen::Vector3d vec3(const mjtNum* p) {
  return {p[0], p[1], p[2]};
}

// MuJoCo's 3x3 matrices are row-major.
Eigen::Vector3d euler_from_matrix(const mjtNum* mat) {
  return roll_pitch_yaw(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(mat));
}

}  // namespace

PickPlaceEnv::PickPlaceEnv(std::shared_ptr<const WorldModel> world)
    : world_(std::move(world)),
      data_(make_data(world_->mj())),
      gravity_compensation_(world_->mj(), world_->ids().arm_root_body) {}

const Observation& PickPlaceEnv::reset(std::uint64_t seed) {
  rng_.reseed(seed);
  start_episode();
  return observation_;
}

void PickPlaceEnv::start_episode() {
  const mjModel* m = world_->mj();
  mjData* d = data_.get();
  const WorldIds& ids = world_->ids();
  // mj_resetData clears everything that carries over between episodes (solver warm
  // start, warnings, applied forces, time), so that an episode depends on its seed only.
  mj_resetData(m, d);
  std::copy(world_->home_qpos().begin(), world_->home_qpos().end(), d->qpos);
  std::copy(world_->home_qvel().begin(), world_->home_qvel().end(), d->qvel);

  const WorldParameters& world = world_->parameters();
  const EpisodeLayout episode =
      sample_episode_layout(rng_, world_->object_spec().half_height_m, world);
  episode_goal_ = episode.goal;
  mjtNum* object_qpos = d->qpos + ids.object_qpos;
  for (int k = 0; k < 3; ++k) object_qpos[k] = episode.object(k);
  object_qpos[3] = 1;
  object_qpos[4] = object_qpos[5] = object_qpos[6] = 0;
  mju_zero(d->qvel + ids.object_dof, 6);

  const Eigen::Vector3d start = world.gripper_start();
  for (int k = 0; k < 3; ++k) {
    d->mocap_pos[3 * ids.gripper_mocap + k] = start(k);
    d->mocap_pos[3 * ids.target_mocap + k] = episode.goal(k);
  }
  for (int k = 0; k < 4; ++k)
    d->mocap_quat[4 * ids.gripper_mocap + k] = world_->gripper_down_quat()(k);
  const double fingers = world.fingers_open_at_reset ? world_->finger_range_m() : 0.0;
  for (int actuator : ids.finger_actuator) d->ctrl[actuator] = fingers;

  mj_forward(m, d);
  if (world.gravity_compensation) gravity_compensation_.apply(m, d);
  update_observation();
  elapsed_steps_ = 0;
  needs_reset_ = false;
}

void PickPlaceEnv::apply_action(const Action& action) {
  mjData* d = data_.get();
  const WorldIds& ids = world_->ids();
  const WorldParameters& world = world_->parameters();
  mjtNum* target = d->mocap_pos + 3 * ids.gripper_mocap;
  for (int k = 0; k < 3; ++k) {
    switch (world.mocap) {
      case MocapControl::kAccumulateClamped:
        target[k] = std::clamp(target[k] + action(k) * layout::kActionPositionScale,
                               layout::kWorkspaceMin(k), layout::kWorkspaceMax(k));
        break;
      case MocapControl::kFromGripper:  // the target starts where the gripper is (the weld's
                                        // lag and any contact that held it back are dropped)
        target[k] = d->site_xpos[3 * ids.grip_site + k] + action(k) * layout::kActionPositionScale;
        break;
    }
  }
  const double finger_scale = world.finger_action_in_metres ? 1.0 : world_->finger_range_m();
  for (std::size_t f = 0; f < 2; ++f) {
    const double q = d->qpos[ids.finger_qpos[f]];
    d->ctrl[ids.finger_actuator[f]] =
        std::clamp(q + action(3) * finger_scale, 0.0, world_->finger_ctrl_max_m());
  }
  if (world.gravity_compensation) gravity_compensation_.apply(world_->mj(), d);
}

void PickPlaceEnv::update_observation() {
  const mjModel* m = world_->mj();
  mjData* d = data_.get();
  const WorldIds& ids = world_->ids();
  // mj_step leaves positions and velocities integrated but the derived quantities from
  // before the last substep: refresh them so the observation is the state after the step.
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_comVel(m, d);

  mjtNum grip_vel[6];
  mjtNum object_vel[6];  // [angular; linear], world-aligned, at the object's origin
  mj_objectVelocity(m, d, mjOBJ_SITE, ids.grip_site, grip_vel, 0);
  mj_objectVelocity(m, d, mjOBJ_BODY, ids.object_body, object_vel, 0);

  const double dt = layout::kStepDuration_s;
  const Eigen::Vector3d grip = vec3(d->site_xpos + 3 * ids.grip_site);
  const Eigen::Vector3d object = vec3(d->xpos + 3 * ids.object_body);
  const Eigen::Vector3d grip_velp = vec3(grip_vel + 3);
  Observation& o = observation_;
  o.segment<3>(obs::kGripperPos) = grip;
  o.segment<3>(obs::kObjectPos) = object;
  o.segment<3>(obs::kObjectRelPos) = object - grip;
  o(obs::kFingerPos) = d->qpos[ids.finger_qpos[0]];
  o(obs::kFingerPos + 1) = d->qpos[ids.finger_qpos[1]];
  o.segment<3>(obs::kObjectEuler) = euler_from_matrix(d->xmat + 9 * ids.object_body);
  o.segment<3>(obs::kObjectRelVel) = (vec3(object_vel + 3) - grip_velp) * dt;
  o.segment<3>(obs::kObjectAngVel) = vec3(object_vel) * dt;
  o.segment<3>(obs::kGripperVel) = grip_velp * dt;
  o(obs::kFingerVel) = d->qvel[ids.finger_dof[0]] * dt;
  o(obs::kFingerVel + 1) = d->qvel[ids.finger_dof[1]] * dt;
}

StepResult PickPlaceEnv::step(std::span<const double> action, std::span<const double> goal,
                              Objective objective) {
  require_steppable(action, goal, needs_reset_, elapsed_steps_);
  const Action clipped = clipped_action(action);
  const Goal agent_goal = Eigen::Map<const Goal>(goal.data());

  const mjModel* m = world_->mj();
  mjData* d = data_.get();
  apply_action(clipped);
  StepResult result;
  for (int k = 0; k < layout::kSubstepsPerStep; ++k) {
    mj_step(m, d);
    result.fault = detect_physics_fault(m, d, world_->ids());
    if (result.fault != PhysicsFault::kNone) break;
  }
  if (result.fault != PhysicsFault::kNone) {
    start_episode();  // a fresh episode from the same random stream
  } else {
    update_observation();
    ++elapsed_steps_;
    needs_reset_ = elapsed_steps_ >= episode_steps();
  }
  result.observation = observation_;
  score_step(result, task_state(), objective, agent_goal, episode_goal_, needs_reset_);
  return result;
}

TaskState PickPlaceEnv::task_state() const {
  return TaskState::from(observation_, episode_goal_, 2 * world_->object_spec().half_width_m);
}

Eigen::Vector3d PickPlaceEnv::objective_goal(Objective objective) const {
  return sim::objective_goal(objective, task_state());
}

}  // namespace pnp::sim
