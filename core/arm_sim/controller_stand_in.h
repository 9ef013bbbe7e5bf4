#pragma once
// What pnp-robot-sim serves: the simulated Panda (SimulatedArm) behind the rules a real
// arm's controller enforces for its network side (robot::ArmController: leases, streams,
// freshness, its own limits, stops), plus what only a simulation has: a seeded scene
// reset, and a choice of clock.
//
// Two clocks. Real time: a thread runs the 1 kHz control loop against the steady clock,
// as the arm would, whatever the network does. Lockstep: the physics advances one policy
// period for each target taken in, and not otherwise, so a gateway can run episodes as
// fast as the computer allows (evaluations, tests) with the same physics.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>
#include <thread>

#include "arm_sim/simulated_arm.h"
#include "arm_sim/simulated_arm_backend.h"
#include "robot/arm_controller.h"

namespace pnp::arm_sim {

struct StandInOptions {
  sim::ObjectShape object = sim::ObjectShape::kBlock;
  sim::WorldProfile world = sim::kDefaultWorldProfile;  // the simulation's world profile
  ClockMode clock = ClockMode::kRealTime;
  std::string base_frame_id = "panda_link0";
  double default_lease_timeout_s = 0.5;  // when a client asks for none (the proto's default)
  double max_lease_timeout_s = 60.0;
  robot::ControllerLimits limits;  // the controller's own: never from the network
  ArmControllerOptions arm;
};

namespace detail {
// The arm and its backend, built before the controller that drives them (a base class
// listed first is constructed first).
struct SimulatedArmHolder {
  explicit SimulatedArmHolder(const StandInOptions& options);
  SimulatedArm arm;
  SimulatedArmBackend backend;
};
}  // namespace detail

class ControllerStandIn : private detail::SimulatedArmHolder, public robot::ArmController {
 public:
  explicit ControllerStandIn(const StandInOptions& options);
  ~ControllerStandIn() override;

  struct SceneReset {
    robot::ControllerReport report;
    Eigen::Vector3d goal_base;
  };
  // Home posture, and the object and goal of the environment's episode `seed`. Needs the
  // lease (FAILED_PRECONDITION otherwise) and an arm that is not stopped.
  SceneReset reset_scene(const std::string& lease_id, std::uint64_t seed);
  // The same from a scene a real arm measured (SimulatedArm::reset_to).
  SceneReset reset_scene_to(const std::string& lease_id, const ObservedScene& scene);

  ClockMode clock() const { return clock_; }

 private:
  void run_real_time(const std::stop_token& stop);
  // The scene `place` sets, under the lease, then the report.
  SceneReset placed(const std::string& lease_id, const std::function<Episode()>& place);

  const ClockMode clock_;
  std::jthread clock_thread_;  // real time only; last member: stops first
};

}  // namespace pnp::arm_sim
