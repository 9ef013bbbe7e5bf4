#pragma once
// One pick-and-place episode driven through the gateway, cycle by cycle at the policy
// rate: read the controller's state, rebuild the policy's observation in the simulation
// frame, ask the inference session for the next action, plan the target as the served
// policy's training world reads an action (its world, from GetServingStatus; frame change,
// rate limit, safety check: robot/target_planner.h), stream it, and take the controller's
// feedback. A refused target is logged with its reason and the arm is held at its
// commanded pose instead. The dead-man: when inference or the controller does not
// answer within the timeout, the arm is held (a hold target, if the stream still takes
// one) and the episode ends with the reason. It also ends on task success (judged from
// the object's perceived pose), at the step cap, or when interrupted (after an E-stop).

#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "clients/robot_gateway/controller_link.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "robot/gateway_config.h"

namespace pnp::gateway {

using EventLog = std::function<void(std::string_view event, const nlohmann::json& fields)>;

struct EpisodeOptions {
  std::uint64_t seed = 0;                    // the stand-in's scene seed (ResetScene)
  bool reset_scene = true;                   // false for a real arm: the scene is what it is
  std::optional<Eigen::Vector3d> goal_base;  // without a scene reset: where the object goes
  bool dry_run = false;                      // compute and log targets, send nothing
};

enum class EpisodeEnd { kSuccess, kStepCap, kDeadman, kInterrupted, kControllerFault };
std::string_view episode_end_name(EpisodeEnd end);

struct EpisodeReport {
  std::uint64_t seed = 0;
  bool success = false;
  EpisodeEnd end = EpisodeEnd::kStepCap;
  std::string reason;  // for kDeadman and kControllerFault (a fault or a bad reading)
  int steps = 0;
  int refused = 0;                             // by the gateway's safety check (held instead)
  int rate_limited = 0;                        // shortened to the speed limit
  int controller_refused = 0;                  // feedback with a status other than OK
  int missed_periods = 0;                      // cycles that overran the policy period (paced only)
  std::vector<double> cycle_us;                // state -> inference -> transform -> send, per cycle
  std::vector<double> state_us, inference_us;  // the cycle's first two phases
};

class GatewayEpisodeRunner {
 public:
  GatewayEpisodeRunner(const robot::GatewayConfig& config, ControllerLink& controller,
                       policy::v1::PolicyService::Stub& policy, EventLog log);

  // Paces cycles to the policy period unless the controller runs in lockstep.
  EpisodeReport run(const EpisodeOptions& options, const std::atomic<bool>& interrupted);

 private:
  struct Cycle;
  const robot::GatewayConfig& config_;
  ControllerLink& controller_;
  policy::v1::PolicyService::Stub& policy_;
  EventLog log_;
  std::uint64_t sequence_ = 0;  // per stream, strictly increasing
};

}  // namespace pnp::gateway
