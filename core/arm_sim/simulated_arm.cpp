#include "arm_sim/simulated_arm.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>

#include "common/error.h"
#include "sim/inverse_kinematics.h"
#include "sim/physics_fault.h"
#include "sim/subtask.h"
#include "sim/task_sampler.h"
#include "sim/world_layout.h"

namespace pnp::arm_sim {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using ArmVector = Eigen::Matrix<double, kJoints, 1>;
using ArmMatrix = Eigen::Matrix<double, kJoints, kJoints>;
using Jacobian = Eigen::Matrix<double, 6, kJoints>;

constexpr double kMaxIkStep_rad = 0.2;  // per iteration: keeps the linearisation valid
// A braking reference slower than this on every joint is at rest (a Panda's joints report
// about 1e-3 rad/s of noise at standstill).
constexpr double kRestVelocity_rad_per_s = 1e-3;
// The share of a joint's acceleration limit the reference plans its braking with: the
// rest is headroom for the velocity loop's lag.
constexpr double kBrakingFraction = 0.8;

std::size_t at(int index) {
  return static_cast<std::size_t>(index);
}

Eigen::Vector3d vec3(const mjtNum* p) {
  return {p[0], p[1], p[2]};
}

Eigen::Matrix3d rotation_from_mj(const mjtNum* mat) {
  // MuJoCo's 3x3 matrices are row-major.
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(mat);
}

Eigen::Quaterniond quaternion_from_mj(const mjtNum* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]);  // MuJoCo stores w, x, y, z
}

void require_positive_option(double value, const char* field) {
  if (!(std::isfinite(value) && value > 0)) {
    throw_invalid_argument(field, "a positive finite number", std::to_string(value));
  }
}

const ArmControllerOptions& validated(const ArmControllerOptions& o) {
  require_positive_option(o.reference_frequency_rad_per_s, "reference_frequency_rad_per_s");
  require_positive_option(o.natural_frequency_rad_per_s, "natural_frequency_rad_per_s");
  require_positive_option(o.damping_ratio, "damping_ratio");
  require_positive_option(o.ik_iterations_per_tick, "ik_iterations_per_tick");
  require_positive_option(o.ik_damping, "ik_damping");
  if (!(std::isfinite(o.ik_nullspace_gain_per_tick) && o.ik_nullspace_gain_per_tick >= 0 &&
        o.ik_nullspace_gain_per_tick < 1)) {
    throw_invalid_argument("ik_nullspace_gain_per_tick", "a number in [0, 1)",
                           std::to_string(o.ik_nullspace_gain_per_tick));
  }
  require_positive_option(o.reach_ik_iterations, "reach_ik_iterations");
  require_positive_option(o.reach_position_tolerance_m, "reach_position_tolerance_m");
  require_positive_option(o.reach_rotation_tolerance_rad, "reach_rotation_tolerance_rad");
  require_positive_option(o.joint_limit_margin_rad, "joint_limit_margin_rad");
  require_positive_option(o.policy_period_s, "policy_period_s");
  require_positive_option(o.default_max_speed_m_per_s, "default_max_speed_m_per_s");
  require_positive_option(o.max_angular_speed_rad_per_s, "max_angular_speed_rad_per_s");
  for (double v : o.velocity_limits_rad_per_s) {
    require_positive_option(v, "velocity_limits_rad_per_s");
  }
  if (!(o.velocity_limit_fraction > 0 && o.velocity_limit_fraction <= 1)) {
    throw_invalid_argument("velocity_limit_fraction", "a number in (0, 1]",
                           std::to_string(o.velocity_limit_fraction));
  }
  for (double a : o.jerk_limits_rad_per_s3) require_positive_option(a, "jerk_limits_rad_per_s3");
  for (double a : o.acceleration_limits_rad_per_s2) {
    require_positive_option(a, "acceleration_limits_rad_per_s2");
  }
  for (double t : o.torque_limits_nm) require_positive_option(t, "torque_limits_nm");
  return o;
}

std::shared_ptr<const sim::WorldModel> require_panda(std::shared_ptr<const sim::WorldModel> world) {
  if (!world) throw_invalid_argument("world", "a loaded world", "none");
  // The limits, base body and gains are the Panda's; Fetch has no real counterpart here.
  if (world->robot() != sim::Robot::kPanda) {
    throw_invalid_argument("robot", "panda", std::string(sim::robot_name(world->robot())));
  }
  return world;
}

std::shared_ptr<const sim::WorldModel> load_panda_world(sim::Robot robot, sim::ObjectShape object,
                                                        sim::WorldProfile world) {
  if (robot != sim::Robot::kPanda) {  // before compiling a world nothing here can drive
    throw_invalid_argument("robot", "panda", std::string(sim::robot_name(robot)));
  }
  return sim::WorldModel::load(robot, object, world);
}

// The arm's and hand's own dynamics (simulated_arm.h), over the world's.
void make_panda(mjModel* m, const sim::WorldIds& ids) {
  for (int joint : ids.arm_joints) {
    m->dof_damping[m->jnt_dofadr[joint]] = kPandaJointDamping;
    m->dof_armature[m->jnt_dofadr[joint]] = kPandaJointArmature;
  }
  for (std::size_t f = 0; f < ids.finger_dof.size(); ++f) {
    m->dof_armature[ids.finger_dof[f]] = kPandaJointArmature;
    const int body = m->dof_bodyid[ids.finger_dof[f]];
    const double scale = kPandaFingerMass_kg / m->body_mass[body];
    m->body_mass[body] = kPandaFingerMass_kg;
    for (int k = 0; k < 3; ++k) m->body_inertia[3 * body + k] *= scale;
    const int actuator = ids.finger_actuator[f];
    m->actuator_forcelimited[actuator] = 1;
    m->actuator_forcerange[2 * actuator] = -kFrankaHandForce_n;
    m->actuator_forcerange[2 * actuator + 1] = kFrankaHandForce_n;
  }
}

int require_id(const mjModel* m, mjtObj type, const char* name) {
  const int id = mj_name2id(m, type, name);
  if (id < 0) throw_internal(std::string("model is missing required element \"") + name + "\"");
  return id;
}

TargetStatus refused(TargetCode code, std::string message) {
  return {code, std::move(message), 0};
}

}  // namespace

JointVector arm_accelerations(double scale, std::string_view field) {
  if (!(scale > 0 && scale <= kMaxAccelerationScale)) {
    throw_invalid_argument(field,
                           fmt::format("a multiple of the Panda's datasheet accelerations in "
                                       "(0, {}]",
                                       kMaxAccelerationScale),
                           fmt::format("{}", scale));
  }
  JointVector out = kPandaDatasheetAccelerations_rad_per_s2;
  for (double& a : out) a *= scale;
  return out;
}

Pose SimulatedArm::Segment::at(double time_s) const {
  const double s = duration_s > 0 ? std::clamp((time_s - start_s) / duration_s, 0.0, 1.0) : 1.0;
  return {from_position + s * (to_position - from_position),
          from_orientation.slerp(s, to_orientation)};
}

SimulatedArm::SimulatedArm(sim::Robot robot, sim::ObjectShape object, sim::WorldProfile world,
                           const ArmControllerOptions& options)
    : SimulatedArm(load_panda_world(robot, object, world), options) {}

SimulatedArm::SimulatedArm(std::shared_ptr<const sim::WorldModel> world,
                           const ArmControllerOptions& options)
    : options_(validated(options)), world_(require_panda(std::move(world))) {
  // A private copy of the training model: the weld that drags the gripper to its mocap
  // target is switched off (the joints are torque-driven instead), the fingers are coupled
  // as a Franka Hand's are (with independent fingers, two saturated finger servos squeezing
  // an off-centre object push the compliant arm sideways instead of centring the object),
  // the arm and hand have the Panda's dynamics (make_panda), and the step is the
  // controller's 1 ms.
  model_.reset(mj_copyModel(nullptr, world_->mj()));
  if (!model_) throw_internal("mj_copyModel failed: out of memory");
  mjModel* m = model_.get();
  m->eq_active[require_id(m, mjOBJ_EQUALITY, "gripper_follows_target")] = 0;
  m->eq_active[require_id(m, mjOBJ_EQUALITY, "fingers_coupled")] = 1;
  m->opt.timestep = kControlPeriod_s;
  make_panda(m, world_->ids());
  {  // the constants derived from masses (subtree masses, invweights) follow them
    const sim::DataPtr constants = sim::make_data(m);
    mj_setConst(m, constants.get());
  }
  // The reachability check's second opinion: the same arm without joint limits.
  unlimited_model_.reset(mj_copyModel(nullptr, m));
  if (!unlimited_model_) throw_internal("mj_copyModel failed: out of memory");
  for (int joint : world_->ids().arm_joints) unlimited_model_->jnt_limited[joint] = 0;
  data_ = sim::make_data(m);
  scratch_ = sim::make_data(m);

  const sim::WorldIds& ids = world_->ids();
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const int joint = ids.arm_joints[j];
    qpos_adr_[j] = m->jnt_qposadr[joint];
    dof_adr_[j] = m->jnt_dofadr[joint];
    lower_[j] = m->jnt_range[2 * joint] + options_.joint_limit_margin_rad;
    upper_[j] = m->jnt_range[2 * joint + 1] - options_.joint_limit_margin_rad;
    home_[j] = world_->home_qpos()[at(qpos_adr_[j])];
  }
  const auto nv = at(m->nv);
  jacp_.assign(3 * nv, 0);
  jacr_.assign(3 * nv, 0);
  accel_.assign(nv, 0);
  mass_accel_.assign(nv, 0);

  // The base is fixed to the world: its pose is read once from the compiled model.
  std::copy(world_->home_qpos().begin(), world_->home_qpos().end(), scratch_->qpos);
  mj_kinematics(m, scratch_.get());
  const int base_body = require_id(m, mjOBJ_BODY, "panda_link0");
  Eigen::Matrix4d base_pose = Eigen::Matrix4d::Identity();
  base_pose.topLeftCorner<3, 3>() = rotation_from_mj(scratch_->xmat + 9 * base_body);
  base_pose.topRightCorner<3, 1>() = vec3(scratch_->xpos + 3 * base_body);
  world_from_base_ = geometry::RigidTransform::from_matrix(base_pose, "panda_link0 pose");
  base_from_world_ = world_from_base_.inverse();

  reset(0);
}

Episode SimulatedArm::reset(std::uint64_t seed) {
  Rng rng(seed);
  return reset(rng);
}

Episode SimulatedArm::reset(Rng& rng) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  const sim::WorldIds& ids = world_->ids();
  // As PickPlaceEnv::start_episode: home state, then the object and goal that the
  // stream samples next (PickPlaceEnv::reset reseeds its generator with the seed).
  mj_resetData(m, d);
  std::copy(world_->home_qpos().begin(), world_->home_qpos().end(), d->qpos);
  std::copy(world_->home_qvel().begin(), world_->home_qvel().end(), d->qvel);
  const sim::EpisodeLayout layout =
      sim::sample_episode_layout(rng, world_->object_spec().half_height_m, world_->parameters());
  mjtNum* object_qpos = d->qpos + ids.object_qpos;
  for (int k = 0; k < 3; ++k) object_qpos[k] = layout.object(k);
  object_qpos[3] = 1;
  object_qpos[4] = object_qpos[5] = object_qpos[6] = 0;
  mju_zero(d->qvel + ids.object_dof, 6);
  for (int k = 0; k < 3; ++k) {
    d->mocap_pos[3 * ids.gripper_mocap + k] = world_->parameters().gripper_start()(k);
    d->mocap_pos[3 * ids.target_mocap + k] = layout.goal(k);
  }
  // As the environment's fingers start: open in the paper world, closed in gym.
  set_gripper(world_->parameters().fingers_open_at_reset ? max_gripper_width_m() : 0.0);
  return start_at_rest({layout.goal, base_from_world_.apply(layout.goal)});
}

// After the scene is placed: derived quantities computed, the arm at rest holding where
// it is, no fault.
Episode SimulatedArm::start_at_rest(const Episode& episode) {
  mj_forward(model_.get(), data_.get());
  episode_ = episode;
  hold_measured_pose();
  torques_.fill(0);
  torques_demanded_.fill(0);
  mode_ = ArmMode::kIdle;
  fault_ = sim::PhysicsFault::kNone;
  return episode_;
}

Episode SimulatedArm::reset_to(const ObservedScene& scene) {
  const mjModel* m = model_.get();
  const sim::WorldIds& ids = world_->ids();
  const auto require_pose = [](const Pose& p, const char* field) {
    if (!p.position_m.allFinite() || !p.orientation.coeffs().allFinite() ||
        std::abs(p.orientation.norm() - 1) > kUnitQuaternionTolerance)
      throw_invalid_argument(field, "a finite position and a unit quaternion", "another pose");
  };
  require_pose(scene.tcp_base, "tcp_base");
  require_pose(scene.object_base, "object_base");
  if (!scene.goal_base.allFinite())
    throw_invalid_argument("goal_base", "a finite position", "a non-finite one");
  if (!(scene.finger_gap_m >= 0 && scene.finger_gap_m <= max_gripper_width_m()))
    throw_invalid_argument("finger_gap_m", fmt::format("0 to {} m", max_gripper_width_m()),
                           std::to_string(scene.finger_gap_m));
  // The posture first, on the scratch data: a pose out of reach changes nothing.
  mjData* s = scratch_.get();
  mj_resetData(m, s);
  std::copy(world_->home_qpos().begin(), world_->home_qpos().end(), s->qpos);
  const Pose tcp_world = world_from_base_.apply(scene.tcp_base);
  sim::IkOptions ik_options;
  ik_options.max_iterations = options_.reach_ik_iterations;
  const sim::IkResult ik = sim::solve_site_ik(
      m, s, ids.grip_site, ids.arm_joints,
      {tcp_world.position_m, tcp_world.orientation.toRotationMatrix()}, home_, ik_options);
  if (ik.position_error_m > options_.reach_position_tolerance_m ||
      ik.rotation_error_rad > options_.reach_rotation_tolerance_rad) {
    throw_invalid_argument("tcp_base", "a grip point pose the arm can take",
                           fmt::format("one inverse kinematics stops {:.4f} m and {:.4f} rad from",
                                       ik.position_error_m, ik.rotation_error_rad));
  }
  mjData* d = data_.get();
  mj_resetData(m, d);
  std::copy(s->qpos, s->qpos + m->nq, d->qpos);
  std::copy(world_->home_qvel().begin(), world_->home_qvel().end(), d->qvel);
  // The fingers: left as the home posture has them if that is the gap measured.
  const double home_gap = d->qpos[ids.finger_qpos[0]] + d->qpos[ids.finger_qpos[1]];
  if (scene.finger_gap_m != home_gap) {
    for (int q : ids.finger_qpos) d->qpos[q] = scene.finger_gap_m / 2;
  }
  const Pose object_world = world_from_base_.apply(scene.object_base);
  mjtNum* object_qpos = d->qpos + ids.object_qpos;
  for (int k = 0; k < 3; ++k) object_qpos[k] = object_world.position_m(k);
  const Eigen::Quaterniond& q = object_world.orientation;
  object_qpos[3] = q.w();
  object_qpos[4] = q.x();
  object_qpos[5] = q.y();
  object_qpos[6] = q.z();
  mju_zero(d->qvel + ids.object_dof, 6);
  const Eigen::Vector3d goal_world = world_from_base_.apply(scene.goal_base);
  for (int k = 0; k < 3; ++k) {
    d->mocap_pos[3 * ids.gripper_mocap + k] = tcp_world.position_m(k);
    d->mocap_pos[3 * ids.target_mocap + k] = goal_world(k);
  }
  set_gripper(scene.finger_gap_m > max_gripper_width_m() / 2 ? max_gripper_width_m() : 0.0);
  return start_at_rest({goal_world, scene.goal_base});
}

TargetStatus SimulatedArm::set_target(const Eigen::Vector3d& position_base_m,
                                      const Eigen::Quaterniond& orientation_base,
                                      double gripper_width_m, double max_speed_m_per_s) {
  if (mode_ == ArmMode::kFault) {
    return refused(TargetCode::kStopped, "the simulation became unstable: call reset()");
  }
  if (mode_ == ArmMode::kStopped) {
    return refused(TargetCode::kStopped, "the arm is stopped: call resume() first");
  }
  if (!position_base_m.allFinite()) {
    return refused(TargetCode::kInvalid,
                   fmt::format("position_base_m: expected finite coordinates, got ({}, {}, {})",
                               position_base_m.x(), position_base_m.y(), position_base_m.z()));
  }
  const double norm = orientation_base.norm();
  if (!orientation_base.coeffs().allFinite() || std::abs(norm - 1.0) > kUnitQuaternionTolerance) {
    return refused(TargetCode::kInvalid,
                   fmt::format("orientation_base: expected a unit quaternion (norm within {} of "
                               "1), got norm {}",
                               kUnitQuaternionTolerance, norm));
  }
  if (!(std::isfinite(gripper_width_m) && gripper_width_m >= 0 &&
        gripper_width_m <= max_gripper_width_m())) {
    return refused(TargetCode::kInvalid,
                   fmt::format("gripper_width_m: expected a width in [0, {}] m, got {}",
                               max_gripper_width_m(), gripper_width_m));
  }
  if (!(std::isfinite(max_speed_m_per_s) && max_speed_m_per_s >= 0)) {
    return refused(TargetCode::kInvalid,
                   fmt::format("max_speed_m_per_s: expected a speed >= 0 (0: default), got {}",
                               max_speed_m_per_s));
  }
  const Pose target = world_from_base_.apply(Pose{position_base_m, orientation_base.normalized()});

  if (TargetStatus reach = check_reachable(target); !reach.accepted()) return reach;

  // Accepted: a new segment from the current command, one policy period long unless the
  // speed limits need longer. The IK restarts from the joint reference, whose TCP pose
  // the segment starts at.
  const double now = data_->time;
  const Pose& from = commanded_world_;
  ik_q_ = command_q_;
  const double speed =
      max_speed_m_per_s > 0 ? max_speed_m_per_s : options_.default_max_speed_m_per_s;
  const double duration =
      std::max({options_.policy_period_s, (target.position_m - from.position_m).norm() / speed,
                from.orientation.angularDistance(target.orientation) /
                    options_.max_angular_speed_rad_per_s});
  segment_ = {from.position_m, target.position_m, from.orientation, target.orientation, now,
              duration};
  target_world_ = target;
  set_gripper(gripper_width_m);
  mode_ = ArmMode::kTracking;
  return {TargetCode::kAccepted, "", duration};
}

TargetStatus SimulatedArm::check_reachable(const Pose& target) {
  // A full solve from the measured posture, on the scratch data, within the joint limits.
  const mjModel* m = model_.get();
  mjData* s = scratch_.get();
  const sim::WorldIds& ids = world_->ids();
  const sim::IkTarget ik_target{target.position_m, target.orientation.toRotationMatrix()};
  sim::IkOptions ik_options;
  ik_options.max_iterations = options_.reach_ik_iterations;
  std::copy(data_->qpos, data_->qpos + m->nq, s->qpos);
  const sim::IkResult ik =
      sim::solve_site_ik(m, s, ids.grip_site, ids.arm_joints, ik_target, home_, ik_options);
  const auto joint_outside = [&](double margin) -> std::optional<std::size_t> {
    for (std::size_t j = 0; j < at(kJoints); ++j) {
      const double q = s->qpos[qpos_adr_[j]];
      if (q < lower_[j] - margin || q > upper_[j] + margin) return j;
    }
    return std::nullopt;
  };
  const auto at_limit = [&](std::size_t j) {
    const double margin = options_.joint_limit_margin_rad;
    return fmt::format("panda_joint{} at {:.4f} rad, range [{:.4f}, {:.4f}]", j + 1,
                       s->qpos[qpos_adr_[j]], lower_[j] - margin, upper_[j] + margin);
  };
  const bool converged = ik.position_error_m <= options_.reach_position_tolerance_m &&
                         ik.rotation_error_rad <= options_.reach_rotation_tolerance_rad;
  if (converged) {
    // solve_site_ik clamps to the model's range, so a solution that needs a joint beyond
    // it ends exactly on the limit (lower_/upper_ sit the margin inside).
    if (const auto j = joint_outside(0)) {
      return refused(TargetCode::kJointLimit, "target needs " + at_limit(*j));
    }
    return {};
  }
  // Not within the limits: a joint limit is to blame if the same solve without limits
  // succeeds; otherwise the pose is out of the arm's reach.
  std::copy(data_->qpos, data_->qpos + m->nq, s->qpos);
  const sim::IkResult unlimited = sim::solve_site_ik(unlimited_model_.get(), s, ids.grip_site,
                                                     ids.arm_joints, ik_target, home_, ik_options);
  if (unlimited.position_error_m <= options_.reach_position_tolerance_m &&
      unlimited.rotation_error_rad <= options_.reach_rotation_tolerance_rad) {
    if (const auto j = joint_outside(options_.joint_limit_margin_rad)) {
      return refused(TargetCode::kJointLimit,
                     "target needs " + at_limit(*j) + " (it is reachable only past that limit)");
    }
  }
  return refused(
      TargetCode::kUnreachable,
      fmt::format("target out of reach: inverse kinematics stops {:.4f} m and "
                  "{:.4f} rad away (tolerance {} m, {} rad)",
                  ik.position_error_m, ik.rotation_error_rad, options_.reach_position_tolerance_m,
                  options_.reach_rotation_tolerance_rad));
}

void SimulatedArm::advance(double seconds) {
  if (!(std::isfinite(seconds) && seconds >= 0)) {
    throw_invalid_argument("seconds", "a finite duration >= 0", std::to_string(seconds));
  }
  if (mode_ == ArmMode::kFault) return;  // frozen until reset(); state() reports it
  // Whole ticks; the slack absorbs the rounding of e.g. 0.04 / 0.001.
  const auto ticks = static_cast<long long>(std::floor(seconds / kControlPeriod_s + 1e-6));
  for (long long i = 0; i < ticks; ++i) {
    tick();
    fault_ = sim::detect_physics_fault(model_.get(), data_.get(), world_->ids());
    if (fault_ != sim::PhysicsFault::kNone) {
      mode_ = ArmMode::kFault;
      break;
    }
  }
  refresh_derived();
  commanded_world_ = forward_kinematics(command_q_);
}

void SimulatedArm::tick() {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  // step1 computes the current state's kinematics, mass matrix and bias forces; the
  // torques written between step1 and step2 act on this very step.
  mj_step1(m, d);
  if (mode_ == ArmMode::kStopped) {
    brake_joint_command();
  } else {
    update_joint_command();
  }
  apply_joint_torques();
  mj_step2(m, d);
}

void SimulatedArm::update_joint_command() {
  const double next_time = data_->time + kControlPeriod_s;
  const JointVector previous_ik = ik_q_;
  ik_iterations(segment_.at(next_time));
  const double dt = kControlPeriod_s;
  const double w = options_.reference_frequency_rad_per_s;
  // The reference follows the IK solution with a velocity made of the solution's own and a
  // correction proportional to the gap (bandwidth w / 2), the correction scaled down as
  // one vector so that no joint moves faster than it could still stop within its gap at
  // its acceleration limit (a saturating PD law overshoots by centimetres at the Panda's
  // limits); a stiff velocity loop (2 w) turns that into an acceleration. The limits then
  // scale the acceleration as one vector (integrate_joint_command).
  const double position_gain = w / 2;
  // Where each joint must come to rest: the IK solution now plus the set point's travel
  // still to come (the segment is linear, so the solution keeps its velocity until then).
  const double remaining_s = std::max(0.0, segment_.start_s + segment_.duration_s - next_time);
  ArmVector ik_velocity, gap, velocity;
  double correction_scale = 1;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    ik_velocity(i) = (ik_q_[j] - previous_ik[j]) / dt;
    gap(i) = ik_q_[j] - command_q_[j];
    const double wanted = position_gain * std::abs(gap(i));
    const double stoppable = stoppable_speed(j, std::abs(gap(i)));
    if (wanted > stoppable) correction_scale = std::min(correction_scale, stoppable / wanted);
  }
  // The whole velocity, too, no faster than each joint can still stop at its rest point:
  // the set point halts at the segment's end, and a reference that had followed it at
  // full speed would overshoot the target (into the table, under a policy that dives).
  double velocity_scale = 1;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    velocity(i) = ik_velocity(i) + correction_scale * position_gain * gap(i);
    const double stoppable = stoppable_speed(j, std::abs(gap(i) + ik_velocity(i) * remaining_s));
    if (std::abs(velocity(i)) > stoppable) {
      velocity_scale = std::min(velocity_scale, stoppable / std::abs(velocity(i)));
    }
  }
  ArmVector accel;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    accel(i) = 2 * w * (velocity_scale * velocity(i) - command_qd_[j]);
  }
  integrate_joint_command(accel);
  if (mode_ == ArmMode::kTracking && segment_.finished(next_time)) mode_ = ArmMode::kHolding;
}

double SimulatedArm::stoppable_speed(std::size_t joint, double distance_rad) const {
  return std::sqrt(2 * kBrakingFraction * options_.acceleration_limits_rad_per_s2[joint] *
                   distance_rad);
}

void SimulatedArm::integrate_joint_command(const ArmVector& accel) {
  const double dt = kControlPeriod_s;
  // The change of acceleration first (jerk), then the acceleration, then the velocity:
  // each scaled as one vector, never clipped joint by joint, which would bend the TCP's
  // path (on this arm, a fast move in x saturates joints 1 and 3, and clipping only them
  // dips the gripper towards the table).
  double jerk_scale = 1;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const double change = std::abs(accel(static_cast<Eigen::Index>(j)) - command_qdd_[j]);
    const double limit = options_.jerk_limits_rad_per_s3[j] * dt;
    if (change > limit) jerk_scale = std::min(jerk_scale, limit / change);
  }
  ArmVector limited;
  double accel_scale = 1;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    limited(i) = command_qdd_[j] + jerk_scale * (accel(i) - command_qdd_[j]);
    const double limit = options_.acceleration_limits_rad_per_s2[j];
    if (std::abs(limited(i)) > limit) {
      accel_scale = std::min(accel_scale, limit / std::abs(limited(i)));
    }
  }
  ArmVector velocity;
  double velocity_scale = 1;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    velocity(i) = command_qd_[j] + accel_scale * limited(i) * dt;
    const double limit = options_.velocity_limit_fraction * options_.velocity_limits_rad_per_s[j];
    if (std::abs(velocity(i)) > limit) {
      velocity_scale = std::min(velocity_scale, limit / std::abs(velocity(i)));
    }
  }
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    double qd = velocity_scale * velocity(static_cast<Eigen::Index>(j));
    double q = command_q_[j] + qd * dt;
    if (q < lower_[j] || q > upper_[j]) {  // only an overshoot gets here: stop at the limit
      q = std::clamp(q, lower_[j], upper_[j]);
      qd = 0;
    }
    command_qdd_[j] = (qd - command_qd_[j]) / dt;
    command_qd_[j] = qd;
    command_q_[j] = q;
  }
}

void SimulatedArm::brake_joint_command() {
  // Towards zero velocity along the current direction: the acceleration that would stop
  // every joint this tick, which the limits then scale down as one vector (so the joints
  // stop together and the TCP stays on its line). Once at rest, it holds there.
  ArmVector accel;
  bool moving = false;
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    accel(static_cast<Eigen::Index>(j)) = -command_qd_[j] / kControlPeriod_s;
    moving = moving || std::abs(command_qd_[j]) > kRestVelocity_rad_per_s;
  }
  if (!moving) {
    command_qd_.fill(0);
    command_qdd_.fill(0);
    return;
  }
  integrate_joint_command(accel);
}

void SimulatedArm::ik_iterations(const Pose& setpoint_world) {
  const mjModel* m = model_.get();
  mjData* s = scratch_.get();
  const int site = world_->ids().grip_site;
  const Eigen::Matrix3d desired = setpoint_world.orientation.toRotationMatrix();
  for (int it = 0; it < options_.ik_iterations_per_tick; ++it) {
    for (std::size_t j = 0; j < at(kJoints); ++j) s->qpos[qpos_adr_[j]] = ik_q_[j];
    mj_kinematics(m, s);
    mj_comPos(m, s);  // mj_jacSite needs cdof and subtree_com
    Vector6 error;
    error.head<3>() = setpoint_world.position_m - vec3(s->site_xpos + 3 * site);
    error.tail<3>() = sim::rotation_error(desired, rotation_from_mj(s->site_xmat + 9 * site));
    mj_jacSite(m, s, jacp_.data(), jacr_.data(), site);
    Jacobian jac;
    ArmVector to_home;
    const auto nv = at(m->nv);
    for (std::size_t j = 0; j < at(kJoints); ++j) {
      const auto dof = at(dof_adr_[j]);
      const auto col = static_cast<Eigen::Index>(j);
      for (std::size_t r = 0; r < 3; ++r) {
        jac(static_cast<Eigen::Index>(r), col) = jacp_[r * nv + dof];
        jac(static_cast<Eigen::Index>(r + 3), col) = jacr_[r * nv + dof];
      }
      to_home(col) = home_[j] - ik_q_[j];
    }
    // Damped pseudo-inverse, and a slow pull towards the home posture in the null space
    // so the redundant elbow does not wander over an episode.
    const Matrix6 jjt = jac * jac.transpose() + options_.ik_damping * Matrix6::Identity();
    const Eigen::Matrix<double, kJoints, 6> pinv =
        jac.transpose() * jjt.ldlt().solve(Matrix6::Identity());
    const ArmVector dq = pinv * error + (ArmMatrix::Identity() - pinv * jac) *
                                            (options_.ik_nullspace_gain_per_tick * to_home);
    for (std::size_t j = 0; j < at(kJoints); ++j) {
      const double step =
          std::clamp(dq(static_cast<Eigen::Index>(j)), -kMaxIkStep_rad, kMaxIkStep_rad);
      ik_q_[j] = std::clamp(ik_q_[j] + step, lower_[j], upper_[j]);
    }
  }
}

void SimulatedArm::apply_joint_torques() {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  const double w = options_.natural_frequency_rad_per_s;
  const double kp = w * w;
  const double kd = 2 * options_.damping_ratio * w;
  // Computed torque: the desired joint acceleration through the current mass matrix,
  // plus Coriolis, centrifugal and gravity forces (qfrc_bias). accel_ is zero outside
  // the arm's dofs, so mj_mulM yields the arm block times the arm accelerations.
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto dof = at(dof_adr_[j]);
    accel_[dof] = command_qdd_[j] + kp * (command_q_[j] - d->qpos[qpos_adr_[j]]) +
                  kd * (command_qd_[j] - d->qvel[dof]);
  }
  mj_mulM(m, d, mass_accel_.data(), accel_.data());
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    const auto dof = at(dof_adr_[j]);
    const double limit = options_.torque_limits_nm[j];
    torques_demanded_[j] = mass_accel_[dof] + d->qfrc_bias[dof];
    torques_[j] = std::clamp(torques_demanded_[j], -limit, limit);
    d->qfrc_applied[dof] = torques_[j];
  }
}

void SimulatedArm::refresh_derived() {
  // mj_step leaves positions integrated but kinematics from before the last step.
  mj_kinematics(model_.get(), data_.get());
  mj_comPos(model_.get(), data_.get());
}

void SimulatedArm::stop() {
  if (mode_ == ArmMode::kFault || mode_ == ArmMode::kStopped) return;
  // The joint reference keeps its position and velocity and brakes from there
  // (brake_joint_command, every tick); the interpolator and the IK are bypassed.
  mode_ = ArmMode::kStopped;
}

void SimulatedArm::resume() {
  if (mode_ != ArmMode::kStopped) return;
  hold_measured_pose();
  mode_ = ArmMode::kHolding;
}

void SimulatedArm::hold_measured_pose() {
  command_q_ = measured_joints();
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    command_q_[j] = std::clamp(command_q_[j], lower_[j], upper_[j]);
  }
  command_qd_.fill(0);
  command_qdd_.fill(0);
  ik_q_ = command_q_;
  commanded_world_ = forward_kinematics(command_q_);
  target_world_ = commanded_world_;
  segment_ = {commanded_world_.position_m,
              commanded_world_.position_m,
              commanded_world_.orientation,
              commanded_world_.orientation,
              data_->time,
              0};
}

void SimulatedArm::set_gripper(double width_m) {
  const mjModel* m = model_.get();
  gripper_width_m_ = width_m;
  // The fingers move symmetrically: each position actuator gets half the opening.
  for (int actuator : world_->ids().finger_actuator) {
    data_->ctrl[actuator] = std::clamp(width_m / 2, m->actuator_ctrlrange[2 * actuator],
                                       m->actuator_ctrlrange[2 * actuator + 1]);
  }
}

Pose SimulatedArm::forward_kinematics(const JointVector& q) {
  const mjModel* m = model_.get();
  mjData* s = scratch_.get();
  for (std::size_t j = 0; j < at(kJoints); ++j) s->qpos[qpos_adr_[j]] = q[j];
  mj_kinematics(m, s);
  const int site = world_->ids().grip_site;
  return {vec3(s->site_xpos + 3 * site),
          Eigen::Quaterniond(rotation_from_mj(s->site_xmat + 9 * site)).normalized()};
}

Pose SimulatedArm::measured_tcp_world() const {
  const int site = world_->ids().grip_site;
  return {vec3(data_->site_xpos + 3 * site),
          Eigen::Quaterniond(rotation_from_mj(data_->site_xmat + 9 * site)).normalized()};
}

JointVector SimulatedArm::measured_joints() const {
  JointVector q{};
  for (std::size_t j = 0; j < at(kJoints); ++j) q[j] = data_->qpos[qpos_adr_[j]];
  return q;
}

ArmState SimulatedArm::state() const {
  const mjData* d = data_.get();
  const sim::WorldIds& ids = world_->ids();
  ArmState s;
  s.mode = mode_;
  s.sim_time_s = d->time;
  s.tcp_world = measured_tcp_world();
  s.tcp_base = base_from_world_.apply(s.tcp_world);
  s.commanded_base = base_from_world_.apply(commanded_world_);
  s.setpoint_base = base_from_world_.apply(segment_.at(d->time));
  s.target_base = base_from_world_.apply(target_world_);
  s.finger_gap_m = d->qpos[ids.finger_qpos[0]] + d->qpos[ids.finger_qpos[1]];
  s.commanded_gripper_width_m = gripper_width_m_;
  s.object_world = {vec3(d->xpos + 3 * ids.object_body),
                    quaternion_from_mj(d->xquat + 4 * ids.object_body).normalized()};
  s.object_base = base_from_world_.apply(s.object_world);
  for (std::size_t j = 0; j < at(kJoints); ++j) {
    s.joint_positions[j] = d->qpos[qpos_adr_[j]];
    s.joint_velocities[j] = d->qvel[dof_adr_[j]];
  }
  s.joint_torques = torques_;
  s.joint_torques_demanded = torques_demanded_;
  return s;
}

bool SimulatedArm::task_success() const {
  const int body = world_->ids().object_body;
  return sim::is_task_success(vec3(data_->xpos + 3 * body), episode_.goal_world);
}

}  // namespace pnp::arm_sim
