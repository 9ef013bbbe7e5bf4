#pragma once
// The Panda's pick-and-place world with its hand moved the way the real arm moves it.
//
// Each step, the policy's action becomes a pose target exactly as the robot gateway makes
// one (robot::plan_target with the gateway's default limits and this arm's own base
// frame: the grip point + 5 cm per unit, kept in the workspace, rate limited and checked;
// a refused plan holds, robot::hold_target), the controller takes it through its own
// limits (take_into_arm), and the simulated Panda tracks it for one 40 ms policy period
// (IK and a 1 kHz joint-space loop within the datasheet's limits: SimulatedArm, the code
// pnp-robot-sim runs). The observation and the episode's goal are rebuilt from what the
// controller reports in its base frame, through the gateway's transform, as the gateway
// rebuilds them (robot::PerceivedObservation: velocities are the change over the
// period). So what a policy learns here is what it meets on the controller, bit for bit
// (tests/core/arm_sim/arm_actuated_env_test.cpp plays both side by side).
//
// Episodes last the arm's 75 steps (sim::episode_steps: the hand needs longer than the
// mocap hand's 50); goals, rewards, predicates and faults are sim::PickPlaceEnv's: the same seed
// gives the same object and goal, a physics fault ends the episode and starts a fresh one
// from the same random stream. Not thread-safe: one owner calls everything.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>

#include "arm_sim/simulated_arm.h"
#include "arm_sim/simulated_arm_backend.h"
#include "common/rng.h"
#include "robot/controller_limits.h"
#include "robot/gateway_config.h"
#include "robot/perceived_observation.h"
#include "robot/safety_limits.h"
#include "sim/actuation.h"
#include "sim/environment.h"

namespace pnp::arm_sim {

struct ArmWorldOptions {
  ArmControllerOptions arm;        // the simulated Panda: the controller's defaults
  robot::ControllerLimits limits;  // the controller's own limits: deploy/robot/controller.json's
  robot::SafetyLimits gateway;     // the gateway's checks: deploy/robot/gateway.json's
};

class ArmActuatedEnv final : public sim::Environment {
 public:
  // `world` must be the Panda's (INVALID_ARGUMENT otherwise); it may be shared.
  explicit ArmActuatedEnv(std::shared_ptr<const sim::WorldModel> world,
                          const ArmWorldOptions& options = {});

  const sim::Observation& reset(std::uint64_t seed) override;
  sim::StepResult step(std::span<const double> action, std::span<const double> goal,
                       sim::Objective objective) override;
  using Environment::step;

  const sim::Observation& observation() const override { return observation_; }
  const sim::Goal& episode_goal() const override { return goal_; }
  sim::TaskState task_state() const override;
  int elapsed_steps() const override { return elapsed_steps_; }
  int episode_steps() const override { return sim::episode_steps(sim::Actuation::kArm); }
  bool needs_reset() const override { return needs_reset_; }

  const SimulatedArm& arm() const { return arm_; }
  const robot::GatewayConfig& gateway() const { return gateway_; }

 private:
  void start_episode();
  void drive(const sim::Action& action);
  void perceive();

  SimulatedArm arm_;
  robot::ControllerLimits limits_;
  SimulatedArmBackend backend_;  // arm_ as the controller takes targets into it
  robot::GatewayConfig gateway_;
  robot::PerceivedObservation perceived_;
  Rng rng_;
  Eigen::Quaterniond held_orientation_base_ = Eigen::Quaterniond::Identity();
  std::optional<robot::PoseTarget> last_accepted_;
  sim::Observation observation_ = sim::Observation::Zero();
  sim::Goal goal_ = sim::Goal::Zero();  // the episode's, as the gateway reads it
  int elapsed_steps_ = 0;
  bool needs_reset_ = true;
};

}  // namespace pnp::arm_sim
