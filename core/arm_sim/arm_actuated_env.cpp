#include "arm_sim/arm_actuated_env.h"

#include "robot/controller_intake.h"
#include "robot/target_planner.h"
#include "sim/actuation.h"
#include "sim/step_rules.h"

namespace pnp::arm_sim {

ArmActuatedEnv::ArmActuatedEnv(std::shared_ptr<const sim::WorldModel> world,
                               const ArmWorldOptions& options)
    : arm_(std::move(world), options.arm),
      limits_(options.limits),
      backend_(arm_, ClockMode::kRealTime) {
  limits_.validate();
  // The gateway as deployed on this arm: its default timing and scale, the given limits,
  // and the simulation-to-base transform read from the model (what calibration measures).
  gateway_.base_from_sim = arm_.base_from_world();
  gateway_.limits = options.gateway;
  gateway_.policy_period_s = options.arm.policy_period_s;
  gateway_.validate();
}

const sim::Observation& ArmActuatedEnv::reset(std::uint64_t seed) {
  rng_.reseed(seed);
  start_episode();
  return observation_;
}

void ArmActuatedEnv::start_episode() {
  const Episode episode = arm_.reset(rng_);
  goal_ = gateway_.base_from_sim.inverse().apply(episode.goal_base);
  // The gateway holds the episode's first commanded orientation for every target.
  held_orientation_base_ = arm_.state().commanded_base.orientation;
  last_accepted_.reset();
  perceived_.reset();
  perceive();
  elapsed_steps_ = 0;
  needs_reset_ = false;
}

void ArmActuatedEnv::perceive() {
  // From the base-frame reports through the gateway's own transform, as the gateway reads
  // them (not from the world-frame state): the same numbers to the last bit.
  const ArmState s = arm_.state();
  const geometry::RigidTransform sim_from_base = gateway_.base_from_sim.inverse();
  const geometry::Pose grip = sim_from_base.apply(s.tcp_base);
  const geometry::Pose object = sim_from_base.apply(s.object_base);
  observation_ =
      perceived_.update({grip.position_m, s.finger_gap_m, object.position_m, object.orientation});
}

void ArmActuatedEnv::drive(const sim::Action& action) {
  const ArmState s = arm_.state();
  const robot::PlannedTarget planned = robot::plan_target(
      gateway_, arm_.world().parameters(),
      {s.commanded_base, s.tcp_base, s.finger_gap_m, held_orientation_base_}, action);
  const std::optional<robot::PoseTarget> target =
      planned.verdict.ok() ? std::optional<robot::PoseTarget>(planned.base)
                           : robot::hold_target(gateway_, last_accepted_, s.commanded_base);
  if (!target) return;  // nothing is sent: the controller holds
  // The stepping is this world's own (step()): the backend only takes the target.
  const robot::IntakeOutcome taken = robot::take_into_arm(
      backend_, limits_,
      {target->pose.position_m, target->pose.orientation, target->gripper_width_m, 0});
  if (taken.accepted()) last_accepted_ = target;
}

sim::StepResult ArmActuatedEnv::step(std::span<const double> action, std::span<const double> goal,
                                     sim::Objective objective) {
  sim::require_steppable(action, goal, needs_reset_, elapsed_steps_);
  const sim::Goal agent_goal = Eigen::Map<const sim::Goal>(goal.data());
  drive(sim::clipped_action(action));
  arm_.advance(gateway_.policy_period_s);
  sim::StepResult result;
  result.fault = arm_.fault();
  if (result.fault != sim::PhysicsFault::kNone) {
    start_episode();  // a fresh episode from the same random stream
  } else {
    perceive();
    ++elapsed_steps_;
    needs_reset_ = elapsed_steps_ >= episode_steps();
  }
  result.observation = observation_;
  sim::score_step(result, task_state(), objective, agent_goal, goal_, needs_reset_);
  return result;
}

sim::TaskState ArmActuatedEnv::task_state() const {
  return sim::TaskState::from(observation_, episode_goal(),
                              2 * arm_.world().object_spec().half_width_m);
}

}  // namespace pnp::arm_sim
