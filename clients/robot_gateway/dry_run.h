#pragma once
// A dry run: the policy's episode played on a shadow arm while the live arm holds, so an
// operator sees the motion (recorded target by target) before anything moves.
//
// The shadow is the simulated Panda of core/arm_sim (what pnp-robot-sim runs), in
// lockstep, behind the controller rules with the live controller's own limits (the
// bridge's --limits file): each target is checked as the live controller would check it.
// Each episode, the shadow is put where the live arm says it is (its grip point, fingers,
// the tracker's object: SimulatedArm::reset_to) with the episode's goal; on a simulated
// live arm, the live scene is first reset to the episode's seed. Every cycle reads the
// live arm too: if it stops, stalls, moves or the object moves, the dry run's episode
// ends there with the reason. The live arm is never sent a target.

#include <Eigen/Core>
#include <atomic>
#include <memory>

#include "arm_sim/controller_stand_in.h"
#include "clients/robot_gateway/controller_link.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "robot/controller_limits.h"
#include "services/common/server_runtime.h"
#include "services/robot_controller/robot_controller_service.h"
#include "services/robot_sim/simulated_scene_service.h"

namespace pnp::gateway {

// How far the live arm's grip point, or the object, may drift while the shadow plays.
inline constexpr double kDryRunDrift_m = 0.005;

class DryRun {
 public:
  // `live` (holding the lease) and `policy` must outlive this. Asks the inference service
  // which world and object the served policy was trained on (the shadow's), throwing as
  // GatewayEpisodeRunner::run does when there is none.
  DryRun(const robot::GatewayConfig& config, const robot::ControllerLimits& live_limits,
         ControllerLink& live, policy::v1::PolicyService::Stub& policy, EventLog log, bool strict,
         const std::atomic<bool>& interrupted);
  ~DryRun();
  DryRun(const DryRun&) = delete;
  DryRun& operator=(const DryRun&) = delete;

  // One episode on the shadow: with options.reset_scene the live (simulated) scene is
  // reset to options.seed first; otherwise options.goal_base is the goal. The report is
  // the shadow's episode; arm_left says the live arm was untouched.
  EpisodeReport run(const EpisodeOptions& options, const std::atomic<bool>& interrupted);

 private:
  std::optional<WatchVerdict> watch_live(const robot::v1::ControllerFeedback& start);

  const robot::GatewayConfig& config_;
  ControllerLink& live_;
  EventLog log_;
  std::unique_ptr<arm_sim::ControllerStandIn> shadow_;
  std::unique_ptr<services::RobotControllerServiceImpl> controller_service_;
  std::unique_ptr<services::SimulatedSceneServiceImpl> scene_service_;
  std::unique_ptr<services::ServerRuntime> server_;
  std::unique_ptr<ControllerLink> shadow_link_;
  std::unique_ptr<GatewayEpisodeRunner> runner_;
};

}  // namespace pnp::gateway
