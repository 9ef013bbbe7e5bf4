#include "clients/robot_gateway/gateway_episode.h"

#include <cmath>
#include <thread>

#include "clients/robot_gateway/policy_session.h"
#include "common/error.h"
#include "robot/controller_reading.h"
#include "robot/perceived_observation.h"
#include "robot/target_planner.h"
#include "services/common/convert.h"
#include "services/common/robot_convert.h"
#include "services/common/time_convert.h"
#include "sim/panda_hand.h"
#include "sim/subtask.h"

namespace pnp::gateway {
namespace {

namespace rv1 = robot::v1;
using Clock = std::chrono::steady_clock;

nlohmann::json to_json(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

double micros(Clock::duration d) {
  return std::chrono::duration<double, std::micro>(d).count();
}

// How long an episode's start waits for an unreachable inference service (restarting,
// say) before the run gives up: nothing moves meanwhile.
constexpr auto kInferenceStartWait = std::chrono::seconds(10);

}  // namespace

policy::v1::ServedRole served_policy(policy::v1::PolicyService::Stub& policy,
                                     const std::atomic<bool>& interrupted) {
  const auto give_up = std::chrono::steady_clock::now() + kInferenceStartWait;
  policy::v1::GetServingStatusResponse status;
  grpc::Status rpc;
  for (;;) {
    grpc::ClientContext context;
    context.set_wait_for_ready(true);  // a reconnecting channel is waited for, not failed
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(100));
    rpc = policy.GetServingStatus(&context, {}, &status);
    if (rpc.error_code() != grpc::StatusCode::DEADLINE_EXCEEDED &&
        rpc.error_code() != grpc::StatusCode::UNAVAILABLE)
      break;
    if (interrupted.load()) throw Error(ErrorCode::kCancelled, "waiting for the inference service");
    if (std::chrono::steady_clock::now() >= give_up) break;
  }
  if (!rpc.ok()) {
    throw Error(ErrorCode::kUnavailable, "the inference service's GetServingStatus failed (code " +
                                             std::to_string(rpc.error_code()) + ") for " +
                                             std::to_string(kInferenceStartWait.count()) +
                                             " s: " + rpc.error_message());
  }
  if (!status.ready() || status.roles().empty()) {
    throw Error(ErrorCode::kFailedPrecondition,
                "the inference service serves no whole policy yet: promote one first");
  }
  return status.roles(0);
}

namespace {

robot::ControllerReading reading_of(const rv1::ControllerFeedback& state) {
  robot::ControllerReading r;
  r.frame_id = state.frame_id();
  r.measured_base = services::from_proto(state.measured());
  r.commanded_base = services::from_proto(state.commanded());
  r.gripper_width_m = state.gripper_width_m();
  if (state.has_object()) r.object_base = services::from_proto(state.object().pose());
  return r;
}

std::string stop_description(const rv1::GetStateResponse& response) {
  return rv1::StopKind_Name(response.stop_kind()) + ": " + response.stop_reason();
}

}  // namespace

std::string_view episode_end_name(EpisodeEnd end) {
  switch (end) {
    case EpisodeEnd::kSuccess:
      return "success";
    case EpisodeEnd::kStepCap:
      return "step_cap";
    case EpisodeEnd::kDeadman:
      return "deadman";
    case EpisodeEnd::kInterrupted:
      return "interrupted";
    case EpisodeEnd::kControllerFault:
      return "controller_fault";
    case EpisodeEnd::kStopped:
      return "stopped";
    case EpisodeEnd::kLeaseLost:
      return "lease_lost";
  }
  return "unknown";
}

bool ends_run(EpisodeEnd end) {
  return end == EpisodeEnd::kInterrupted || end == EpisodeEnd::kStopped ||
         end == EpisodeEnd::kLeaseLost;
}

// Everything one episode keeps between its cycles.
struct GatewayEpisodeRunner::Episode {
  Episode(const EpisodeOptions& o, const std::atomic<bool>& i, policy::v1::PolicyService::Stub& p,
          int max_steps, sim::WorldProfile w)
      : options(o),
        interrupted(i),
        session(p, max_steps),
        world(w),
        world_parameters(sim::world_parameters(w)) {}

  const EpisodeOptions& options;
  const std::atomic<bool>& interrupted;
  PolicySession session;
  bool session_broken = false;
  const sim::WorldProfile world;
  const sim::WorldParameters& world_parameters;
  robot::PerceivedObservation perceived;
  Eigen::Vector3d goal_sim = Eigen::Vector3d::Zero();
  Eigen::Quaterniond held_orientation_base = Eigen::Quaterniond::Identity();
  std::optional<robot::PoseTarget> last_accepted;  // what hold() may send again
  int waited = 0;  // periods waited for the arm since the policy was last asked
  bool lockstep = false;
  Clock::time_point next_cycle;
  EpisodeReport report;

  void end(EpisodeEnd end, std::string reason) {
    report.end = end;
    report.reason = std::move(reason);
  }
};

GatewayEpisodeRunner::GatewayEpisodeRunner(const robot::GatewayConfig& config,
                                           ControllerLink& controller,
                                           policy::v1::PolicyService::Stub& policy, EventLog log,
                                           bool strict)
    : config_(config),
      controller_(controller),
      policy_(policy),
      log_(std::move(log)),
      strict_(strict) {}

// A policy meets here what it was trained for only if it was trained on a Panda through
// the arm's controller: one trained on the mocap hand (which reaches each target within a
// step) lags on a real arm and succeeds less (docs/RESULTS.md). Warned once per run.
void GatewayEpisodeRunner::check_served_policy(const policy::v1::ServedRole& served) {
  if (policy_checked_) return;
  std::string why;
  if (served.robot() != common::v1::ROBOT_UNSPECIFIED && served.robot() != common::v1::ROBOT_PANDA)
    why = "it was trained on robot " + common::v1::Robot_Name(served.robot()) + ", not the Panda";
  else if (served.actuation() != common::v1::ACTUATION_ARM)
    why =
        "it was trained on the mocap hand, not through the arm's controller (train it with "
        "--actuation arm)";
  policy_checked_ = true;
  if (why.empty()) return;
  const std::string message = "the served policy does not match this arm: " + why;
  if (strict_) throw Error(ErrorCode::kFailedPrecondition, message + " (--strict)");
  log_("policy_warning", {{"reason", message}});
}

// Targets name the policy's grip point; a controller tracking another point (a real
// Franka Hand left at its default 0.1034 m) would put every grasp 1 cm off.
void GatewayEpisodeRunner::check_controller_tcp() {
  if (tcp_checked_) return;
  const double tcp = controller_.state().tcp_from_flange_m();
  if (!(std::abs(tcp - sim::kGripPointFromFlange_m) <= sim::kTcpTolerance_m)) {
    throw Error(ErrorCode::kFailedPrecondition,
                "the controller (" + controller_.address() + ") tracks a grip point " +
                    std::to_string(tcp) + " m from the flange; the policy's is " +
                    std::to_string(sim::kGripPointFromFlange_m) +
                    " m (set the controller's end-effector frame to it)");
  }
  tcp_checked_ = true;
}

EpisodeReport GatewayEpisodeRunner::run(const EpisodeOptions& options,
                                        const std::atomic<bool>& interrupted) {
  // Before anything moves: the served world and the controller's grip point. Ctrl-C while
  // they are asked for ends the episode before its first cycle, and the arm is still
  // emergency-stopped below, as on Ctrl-C in a cycle; any other failure here is the run's.
  sim::WorldProfile world = sim::kDefaultWorldProfile;
  std::optional<std::string> interrupted_early;
  try {
    const policy::v1::ServedRole served = served_policy(policy_, interrupted);
    world = services::from_proto(served.world(), "served world");
    check_served_policy(served);
    check_controller_tcp();
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kCancelled && !interrupted.load()) throw;
    interrupted_early = std::string("interrupted: ") + e.what();
  }
  Episode episode(options, interrupted, policy_, config_.max_episode_steps, world);
  episode.report.seed = options.seed;
  if (interrupted_early) episode.end(EpisodeEnd::kInterrupted, *interrupted_early);
  try {
    if (!interrupted_early) run_cycles(episode);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::kCancelled || interrupted.load()) {
      episode.end(EpisodeEnd::kInterrupted, std::string("interrupted: ") + e.what());
    } else {
      episode.end(EpisodeEnd::kControllerFault, e.what());
    }
    log_("fault", {{"step", episode.report.steps}, {"reason", episode.report.reason}});
  }
  if (interrupted.load() && episode.report.end != EpisodeEnd::kInterrupted) {
    episode.end(EpisodeEnd::kInterrupted, "interrupted by the operator");
  }
  leave_arm_safe(episode);
  if (!episode.session_broken) {
    try {
      episode.session.finish();
    } catch (const std::exception&) {  // the session is abandoned with the episode
    }
  }
  const EpisodeReport& report = episode.report;
  log_("episode_end", {{"seed", options.seed},
                       {"success", report.success},
                       {"end", episode_end_name(report.end)},
                       {"reason", report.reason},
                       {"arm_left", report.arm_left},
                       {"steps", report.steps},
                       {"refused", report.refused},
                       {"controller_refused", report.controller_refused},
                       {"missed_periods", report.missed_periods}});
  return std::move(episode.report);
}

// How the arm is left: still tracking its last accepted target after a normal end; a
// protective stop after a fault (the gateway no longer knows the arm's state); an
// emergency stop on Ctrl-C. A stop that cannot be delivered is reported, not hidden.
void GatewayEpisodeRunner::leave_arm_safe(Episode& episode) {
  EpisodeReport& report = episode.report;
  controller_.close_stream();
  const bool fault =
      report.end == EpisodeEnd::kDeadman || report.end == EpisodeEnd::kControllerFault;
  if (report.end != EpisodeEnd::kInterrupted && !fault) {
    report.arm_left = report.end == EpisodeEnd::kStopped ? "emergency_stop" : "tracking";
    return;
  }
  const auto kind = fault ? rv1::STOP_KIND_PROTECTIVE : rv1::STOP_KIND_EMERGENCY;
  const std::string reason =
      fault ? "gateway fault: " + report.reason : std::string("gateway interrupted (Ctrl-C)");
  try {
    controller_.stop(reason, kind, config_.deadman_timeout());
    report.arm_left = fault ? "protective_stop" : "emergency_stop";
  } catch (const Error& e) {
    report.arm_left = std::string("stop not delivered: ") + e.what();
  }
  log_("stop",
       {{"kind", rv1::StopKind_Name(kind)}, {"reason", reason}, {"arm_left", report.arm_left}});
}

// The episode's start: an emergency stop or another lease holder ends the run before
// anything moves; the gateway's own protective stop of the previous episode is cleared. A
// lease that lapsed between episodes (the gateway waited for a restarting inference
// service, and the arm held meanwhile) is taken again if nobody else took it.
bool GatewayEpisodeRunner::start_episode(Episode& episode) {
  rv1::GetStateResponse before = controller_.state();
  if (before.lease_holder().empty() && controller_.has_lease()) {
    controller_.reacquire_lease();
    log_("lease_reacquired", {{"reason", "the lease lapsed between episodes"}});
    before = controller_.state();
  }
  if (before.lease_holder() != controller_.client_name()) {
    episode.end(EpisodeEnd::kLeaseLost, "the lease is held by \"" + before.lease_holder() +
                                            "\", not \"" + controller_.client_name() + "\"");
    return false;
  }
  if (before.stop_kind() == rv1::STOP_KIND_EMERGENCY) {
    episode.end(EpisodeEnd::kStopped, "the arm is emergency-stopped (" + before.stop_reason() +
                                          "): an operator must clear it (pnpctl robot resume "
                                          "--ack REASON)");
    return false;
  }
  if (before.stop_kind() == rv1::STOP_KIND_PROTECTIVE) {
    controller_.clear_protective_stop();
    log_("protective_stop_cleared", {{"reason", before.stop_reason()}});
  }
  rv1::ControllerFeedback start;
  if (episode.options.reset_scene) {
    const rv1::ResetSceneResponse scene = controller_.reset_scene(episode.options.seed);
    episode.goal_sim = config_.base_from_sim.inverse().apply(services::from_proto(scene.goal()));
    start = scene.state();
  } else {
    if (!episode.options.goal_base || !episode.options.goal_base->allFinite()) {
      throw_invalid_argument(
          "goal", "a finite goal position (base frame) when the scene is not reset", "none");
    }
    episode.goal_sim = config_.base_from_sim.inverse().apply(*episode.options.goal_base);
    start = before.state();
  }
  if (auto bad = robot::reading_error(reading_of(start), config_.base_frame_id,
                                      config_.limits.quaternion_norm_tolerance)) {
    episode.end(EpisodeEnd::kControllerFault, "bad controller reading at the start: " + *bad);
    return false;
  }
  episode.report.goal_sim = {episode.goal_sim.x(), episode.goal_sim.y(), episode.goal_sim.z()};
  episode.held_orientation_base = services::from_proto(start.commanded()).orientation;
  episode.lockstep = before.lockstep();
  controller_.open_stream();
  log_("episode_start", {{"seed", episode.options.seed},
                         {"world", sim::world_profile_name(episode.world)},
                         {"goal_sim_m", to_json(episode.goal_sim)},
                         {"lockstep", episode.lockstep}});
  return true;
}

void GatewayEpisodeRunner::run_cycles(Episode& episode) {
  if (!start_episode(episode)) return;
  episode.next_cycle = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config_.policy_period_s));
  while (cycle(episode)) {
    ++episode.report.steps;
    if (episode.lockstep) continue;
    episode.next_cycle += period;
    const auto now = Clock::now();
    if (now > episode.next_cycle) {
      ++episode.report.missed_periods;
      episode.next_cycle = now;
    } else {
      std::this_thread::sleep_until(episode.next_cycle);
    }
  }
}

// One cycle; false when the episode ends (its end and reason set).
bool GatewayEpisodeRunner::cycle(Episode& episode) {
  EpisodeReport& report = episode.report;
  if (episode.interrupted.load()) {
    episode.end(EpisodeEnd::kInterrupted, "interrupted by the operator");
    return false;
  }
  const auto deadman = config_.deadman_timeout();
  const auto start = Clock::now();
  const auto response = controller_.state(deadman);
  report.state_us.push_back(micros(Clock::now() - start));
  if (!response) {
    episode.end(EpisodeEnd::kDeadman, "the controller did not answer GetState within " +
                                          std::to_string(deadman.count()) + " ms");
    return false;
  }
  const rv1::ControllerFeedback& state = response->state();
  if (response->lease_holder() != controller_.client_name()) {
    episode.end(EpisodeEnd::kLeaseLost,
                "the lease is now held by \"" + response->lease_holder() + "\"");
    return false;
  }
  if (state.mode() == rv1::CONTROLLER_MODE_FAULT) {
    episode.end(EpisodeEnd::kControllerFault, "the controller reports a fault");
    return false;
  }
  if (state.mode() == rv1::CONTROLLER_MODE_STOPPED) {
    episode.end(EpisodeEnd::kStopped, "the arm was stopped (" + stop_description(*response) + ")");
    return false;
  }
  if (episode.options.watch) {
    if (auto verdict = episode.options.watch()) {
      episode.end(verdict->end, std::move(verdict->reason));
      log_("watch", {{"step", report.steps}, {"reason", report.reason}});
      return false;
    }
  }
  const robot::ControllerReading reading = reading_of(state);
  if (auto bad = robot::reading_error(reading, config_.base_frame_id,
                                      config_.limits.quaternion_norm_tolerance)) {
    episode.end(EpisodeEnd::kControllerFault, "bad controller reading: " + *bad);
    log_("bad_reading", {{"step", report.steps}, {"reason", report.reason}});
    return false;
  }
  const geometry::RigidTransform sim_from_base = config_.base_from_sim.inverse();
  const geometry::Pose measured_sim = sim_from_base.apply(reading.measured_base);
  const geometry::Pose object_sim = sim_from_base.apply(*reading.object_base);
  if (sim::is_task_success(object_sim.position_m, episode.goal_sim)) {
    report.success = true;
    episode.end(EpisodeEnd::kSuccess, "");
    return false;
  }
  if (report.decisions >= config_.max_episode_steps) {
    episode.end(EpisodeEnd::kStepCap, "");
    return false;
  }
  sim::Observation observation;
  try {
    observation = episode.perceived.update({measured_sim.position_m, reading.gripper_width_m,
                                            object_sim.position_m, object_sim.orientation});
  } catch (const Error& e) {
    // A reading the policy cannot be given: nothing is sent (the arm holds its last
    // target) and the episode ends with the reason; the next episode goes on.
    episode.end(EpisodeEnd::kControllerFault, std::string("bad controller reading: ") + e.what());
    log_("bad_reading", {{"step", report.steps}, {"reason", report.reason}});
    return false;
  }

  if (waiting_for_arm(episode, reading)) {
    if (episode.options.trace) {
      log_("arrival_wait",
           {{"step", report.steps}, {"distance_m", distance_to_last_target(episode, reading)}});
    }
    ++report.arrival_waits;
    ++episode.waited;
    const bool go_on = hold(episode, state);
    report.cycle_us.push_back(micros(Clock::now() - start));
    return go_on;
  }
  episode.waited = 0;
  ++report.decisions;
  const auto asked = Clock::now();
  std::optional<Prediction> prediction;
  if (episode.session.ask(observation, episode.goal_sim)) {
    prediction = episode.session.answer(asked + deadman, episode.interrupted);
  }
  report.inference_us.push_back(micros(Clock::now() - asked));
  if (prediction) {
    report.path.push_back(
        {{measured_sim.position_m.x(), measured_sim.position_m.y(), measured_sim.position_m.z()},
         {object_sim.position_m.x(), object_sim.position_m.y(), object_sim.position_m.z()},
         services::subtask_index(static_cast<common::v1::Subtask>(prediction->subtask))});
  }
  if (!prediction) {
    episode.session_broken = true;  // a late answer would pair with the wrong request
    if (episode.interrupted.load()) {
      episode.end(EpisodeEnd::kInterrupted, "interrupted by the operator");
    } else {
      episode.end(EpisodeEnd::kDeadman,
                  "inference did not answer within " + std::to_string(deadman.count()) +
                      " ms: nothing more is sent, the arm holds its last accepted target");
      log_("deadman", {{"step", report.steps}, {"reason", report.reason}});
    }
    return false;
  }

  const robot::PlannedTarget planned =
      robot::plan_target(config_, episode.world_parameters,
                         {reading.commanded_base, reading.measured_base, reading.gripper_width_m,
                          episode.held_orientation_base},
                         prediction->action);
  if (!planned.verdict.ok()) {
    ++report.refused;
    log_("refused", {{"step", report.steps},
                     {"check", robot::safety_refusal_name(*planned.verdict.refusal)},
                     {"reason", planned.verdict.reason},
                     {"action",
                      {prediction->action(0), prediction->action(1), prediction->action(2),
                       prediction->action(3)}}});
    const bool go_on = hold(episode, state);
    report.cycle_us.push_back(micros(Clock::now() - start));
    return go_on;
  }
  if (planned.rate_limited) ++report.rate_limited;
  if (planned.clamped) ++report.clamped;
  if (episode.options.trace) {
    log_("cycle", {{"step", report.steps},
                   {"grip_sim_m", to_json(measured_sim.position_m)},
                   {"object_sim_m", to_json(object_sim.position_m)},
                   {"gripper_width_m", reading.gripper_width_m},
                   {"subtask", prediction->subtask},
                   {"action",
                    {prediction->action(0), prediction->action(1), prediction->action(2),
                     prediction->action(3)}},
                   {"target_sim_m", to_json(planned.sim.position_m)},
                   {"target_gripper_width_m", planned.base.gripper_width_m}});
  }
  const auto send_start = Clock::now();
  const bool go_on = send_and_take_feedback(episode, planned.base);
  report.send_us.push_back(micros(Clock::now() - send_start));
  report.cycle_us.push_back(micros(Clock::now() - start));
  return go_on;
}

// How far the measured grip point is from the last accepted target (which must exist).
double GatewayEpisodeRunner::distance_to_last_target(const Episode& episode,
                                                     const robot::ControllerReading& reading) {
  return (reading.measured_base.position_m - episode.last_accepted->pose.position_m).norm();
}

// Whether this cycle waits for the arm to reach the last accepted target instead of asking
// the policy (GatewayConfig::max_arrival_wait_periods).
bool GatewayEpisodeRunner::waiting_for_arm(const Episode& episode,
                                           const robot::ControllerReading& reading) const {
  if (config_.max_arrival_wait_periods == 0 || !episode.last_accepted) return false;
  if (episode.waited >= config_.max_arrival_wait_periods) return false;
  return distance_to_last_target(episode, reading) > config_.arrival_tolerance_m;
}

// After a refusal, or while waiting for the arm: the last accepted target again, if it
// still passes the checks from where the arm is commanded now; otherwise nothing (the
// controller holds by itself). False when the episode must end.
bool GatewayEpisodeRunner::hold(Episode& episode, const rv1::ControllerFeedback& state) {
  const std::optional<robot::PoseTarget> again =
      robot::hold_target(config_, episode.last_accepted, services::from_proto(state.commanded()));
  if (!again) {
    ++episode.report.held_without_target;
    return true;
  }
  return send_and_take_feedback(episode, *again);
}

// False when the episode must end (no answer, a stop, a lost lease).
bool GatewayEpisodeRunner::send_and_take_feedback(Episode& episode,
                                                  const robot::PoseTarget& planned) {
  EpisodeReport& report = episode.report;
  rv1::PoseTarget target;
  target.set_sequence(++sequence_);
  target.set_frame_id(config_.base_frame_id);
  services::to_proto(std::chrono::system_clock::now(), *target.mutable_stamp());
  services::to_proto(planned.pose, *target.mutable_pose());
  target.set_gripper_width_m(planned.gripper_width_m);
  const auto deadman = config_.deadman_timeout();
  if (episode.options.record) episode.options.record(episode.options.seed, report.steps, planned);
  const bool sent = controller_.send(target);
  const auto feedback = sent ? controller_.feedback(Clock::now() + deadman) : std::nullopt;
  if (!feedback) {
    episode.end(EpisodeEnd::kDeadman, sent ? "the controller did not answer a target within " +
                                                 std::to_string(deadman.count()) + " ms"
                                           : std::string("the drive stream broke"));
    log_("deadman", {{"step", report.steps}, {"reason", report.reason}});
    return false;
  }
  switch (feedback->status()) {
    case rv1::CONTROLLER_STATUS_OK:
      episode.last_accepted = planned;
      return true;
    case rv1::CONTROLLER_STATUS_STOPPED: {
      // Why, as the controller reports it (what an operator acknowledges), if it says.
      std::string why = "the controller refused a target: the arm is stopped";
      try {
        if (const auto stopped = controller_.state(deadman))
          why += " (" + stop_description(*stopped) + ")";
      } catch (const std::exception&) {  // the stop is reported without its reason
      }
      episode.end(EpisodeEnd::kStopped, std::move(why));
      return false;
    }
    case rv1::CONTROLLER_STATUS_LEASE_LOST:
      episode.end(EpisodeEnd::kLeaseLost, "the controller refused a target: lease lost");
      return false;
    default:
      break;
  }
  ++report.controller_refused;
  ++report.controller_refusals_by_reason[rv1::ControllerStatus_Name(feedback->status())];
  log_(
      "controller_refused",
      {{"step", report.steps},
       {"status", rv1::ControllerStatus_Name(feedback->status())},
       {"errors", std::vector<std::string>(feedback->errors().begin(), feedback->errors().end())}});
  return true;
}

}  // namespace pnp::gateway
