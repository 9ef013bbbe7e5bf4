#pragma once
// One pick-and-place episode driven through the gateway, cycle by cycle at the policy
// rate: read the controller's state (within the dead-man time) and check it as a whole,
// rebuild the policy's observation in the simulation frame, ask the inference session for
// the next action, plan the target as the served policy's training world reads an action
// (its world, from GetServingStatus; frame change, rate limit, safety check:
// robot/target_planner.h), stream it, and take the controller's feedback.
//
// Hold means hold: a target the gateway refuses is replaced by the last target the
// controller accepted, checked again, or by nothing; never by an older pose read back.
// Every wait is bounded by the dead-man time and gives way to Ctrl-C. Any fault in a cycle
// (a stalled or lost controller, a bad reading, a late answer from inference) ends that
// episode with the reason and a protective stop (which the next episode clears as the
// lease holder), and the run goes on. An emergency stop (Ctrl-C here, or anyone's) or a
// lost lease ends the run: clearing an emergency stop is an operator's action
// (pnpctl robot resume --ack REASON).

#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "clients/robot_gateway/controller_link.h"
#include "plot/episode_view_svg.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "robot/controller_reading.h"
#include "robot/gateway_config.h"
#include "robot/safety_limits.h"
#include "robot/target_planner.h"

namespace pnp::gateway {

using EventLog = std::function<void(std::string_view event, const nlohmann::json& fields)>;

enum class EpisodeEnd;
struct WatchVerdict;

struct EpisodeOptions {
  std::uint64_t seed = 0;                    // the stand-in's scene seed (ResetScene)
  bool reset_scene = true;                   // false for a real arm: the scene is what it is
  std::optional<Eigen::Vector3d> goal_base;  // without a scene reset: where the object goes
  // Log a "cycle" event every cycle (simulation frame: grip point, object, opening, the
  // subtask and action the policy chose, the planned target): what an operator or a
  // failure analysis reads back. Off by default: 25 lines a second.
  bool trace = false;
  // Each cycle, after the controller's state is read: a reason to end the episode there
  // (a dry run's watch on the live arm, which must hold while the shadow plays).
  std::function<std::optional<WatchVerdict>()> watch;
  // Every target sent, as sent (a hold's repeat included): the episode's record.
  std::function<void(std::uint64_t seed, int step, const robot::PoseTarget& target)> record;
};

enum class EpisodeEnd {
  kSuccess,
  kStepCap,
  kDeadman,          // the controller or inference did not answer in time
  kInterrupted,      // Ctrl-C: the arm was emergency-stopped
  kControllerFault,  // a fault, a bad reading or a failed call
  kStopped,          // the arm is emergency-stopped (by anyone): an operator must clear it
  kLeaseLost,        // another client holds the arm, or the lease lapsed
};
std::string_view episode_end_name(EpisodeEnd end);

struct WatchVerdict {
  EpisodeEnd end;
  std::string reason;
};
// Whether no further episode may start after this one (the run ends).
bool ends_run(EpisodeEnd end);

struct EpisodeReport {
  std::uint64_t seed = 0;
  bool success = false;
  EpisodeEnd end = EpisodeEnd::kStepCap;
  std::string reason;           // for every end but success and the step cap
  std::string arm_left;         // "tracking", "protective_stop", "emergency_stop" or why not
  int steps = 0;                // cycles
  int decisions = 0;            // cycles that asked the policy (max_episode_steps counts these)
  int arrival_waits = 0;        // cycles that waited for the arm instead (the target sent again)
  int refused = 0;              // by the gateway's safety check (held instead)
  int held_without_target = 0;  // refusals with no checked target to hold: nothing sent
  int rate_limited = 0;         // shortened to the speed limit
  int clamped = 0;              // brought into the gateway's workspace box
  int controller_refused = 0;   // feedback with a status other than OK
  std::map<std::string, int> controller_refusals_by_reason;  // by ControllerStatus name
  int missed_periods = 0;                      // cycles that overran the policy period (paced only)
  std::vector<double> cycle_us;                // state -> inference -> transform -> send, per cycle
  std::vector<double> state_us, inference_us;  // the cycle's first two phases
  std::vector<double> send_us;  // the target sent and its feedback taken (cycles that send)
  // What the episode view draws (simulation frame): the goal, and at each decision the
  // grip point, the object and the subtask the policy chose.
  std::array<double, 3> goal_sim{};
  std::vector<plot::EpisodeFrame> path;
};

// What the served policy was trained on (its world reads actions: they are planned that
// way). Waits up to 10 s for the inference service to be reachable (Ctrl-C ends the wait
// within 100 ms, as kCancelled); UNAVAILABLE after that, FAILED_PRECONDITION while no
// whole policy is served.
policy::v1::ServedRole served_policy(policy::v1::PolicyService::Stub& policy,
                                     const std::atomic<bool>& interrupted);

class GatewayEpisodeRunner {
 public:
  // Keeps references: `config`, `controller` and `policy` must outlive the runner. A
  // served policy trained for another arm (another robot, or the mocap hand rather than
  // the arm's controller) is warned about once (a "policy_warning" event); `strict`
  // refuses it instead.
  GatewayEpisodeRunner(const robot::GatewayConfig& config, ControllerLink& controller,
                       policy::v1::PolicyService::Stub& policy, EventLog log, bool strict = false);
  GatewayEpisodeRunner(robot::GatewayConfig&& config, ControllerLink& controller,
                       policy::v1::PolicyService::Stub& policy, EventLog log,
                       bool strict = false) = delete;

  // Paces cycles to the policy period unless the controller runs in lockstep. Throws
  // (before anything moves) only when the run cannot drive this arm with this policy: no
  // served policy (FAILED_PRECONDITION, or UNAVAILABLE when inference cannot say), a
  // controller whose grip point differs from the policy's, or (strict) a policy trained
  // for another arm (FAILED_PRECONDITION). Every other fault ends the episode with its
  // reason.
  EpisodeReport run(const EpisodeOptions& options, const std::atomic<bool>& interrupted);

 private:
  struct Episode;
  void check_controller_tcp();
  void check_served_policy(const policy::v1::ServedRole& served);
  void run_cycles(Episode& episode);
  bool start_episode(Episode& episode);
  bool cycle(Episode& episode);
  bool waiting_for_arm(const Episode& episode, const robot::ControllerReading& reading) const;
  static double distance_to_last_target(const Episode& episode,
                                        const robot::ControllerReading& reading);
  bool hold(Episode& episode, const robot::v1::ControllerFeedback& state);
  bool send_and_take_feedback(Episode& episode, const robot::PoseTarget& target);
  void leave_arm_safe(Episode& episode);

  const robot::GatewayConfig& config_;
  ControllerLink& controller_;
  policy::v1::PolicyService::Stub& policy_;
  EventLog log_;
  bool strict_ = false;
  std::uint64_t sequence_ = 0;  // per stream, strictly increasing
  bool tcp_checked_ = false;
  bool policy_checked_ = false;
};

}  // namespace pnp::gateway
