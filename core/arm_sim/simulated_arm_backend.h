#pragma once
// The simulated Panda as a controller's arm (robot::ArmBackend): what pnp-robot-sim's
// controller and the arm-actuated training world drive. In lockstep the physics advances
// one policy period per target the controller answers; otherwise its owner advances it.

#include "arm_sim/simulated_arm.h"
#include "robot/arm_backend.h"

namespace pnp::arm_sim {

enum class ClockMode { kRealTime, kLockstep };

// The controller's view of a simulated arm's state.
robot::BackendReading reading_of(const ArmState& state);

class SimulatedArmBackend final : public robot::ArmBackend {
 public:
  // `arm` must outlive the backend.
  SimulatedArmBackend(SimulatedArm& arm, ClockMode clock) : arm_(arm), clock_(clock) {}

  robot::BackendReading reading() const override { return reading_of(arm_.state()); }
  robot::IntakeOutcome command(const robot::ArmTarget& target) override;
  double default_max_speed_m_per_s() const override {
    return arm_.options().default_max_speed_m_per_s;
  }
  void stop() override { arm_.stop(); }
  void resume() override { arm_.resume(); }
  void after_target() override;

 private:
  SimulatedArm& arm_;
  ClockMode clock_;
};

}  // namespace pnp::arm_sim
