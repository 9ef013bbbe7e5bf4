#include "clients/robot_gateway/gateway_episode.h"

#include <thread>

#include "clients/robot_gateway/policy_session.h"
#include "common/error.h"
#include "robot/perceived_observation.h"
#include "robot/target_planner.h"
#include "services/common/convert.h"
#include "services/common/robot_convert.h"
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

// The world the served policy was trained in: its actions are planned the way that world
// reads them. FAILED_PRECONDITION while no whole policy is served.
sim::WorldProfile served_world(policy::v1::PolicyService::Stub& policy) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  policy::v1::GetServingStatusResponse status;
  const grpc::Status rpc = policy.GetServingStatus(&context, {}, &status);
  if (!rpc.ok()) {
    throw Error(ErrorCode::kUnavailable, "the inference service's GetServingStatus failed (code " +
                                             std::to_string(rpc.error_code()) +
                                             "): " + rpc.error_message());
  }
  if (!status.ready() || status.roles().empty()) {
    throw Error(ErrorCode::kFailedPrecondition,
                "the inference service serves no whole policy yet: promote one first");
  }
  return services::from_proto(status.roles(0).world(), "served world");
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
  }
  return "unknown";
}

GatewayEpisodeRunner::GatewayEpisodeRunner(const robot::GatewayConfig& config,
                                           ControllerLink& controller,
                                           policy::v1::PolicyService::Stub& policy, EventLog log)
    : config_(config), controller_(controller), policy_(policy), log_(std::move(log)) {}

EpisodeReport GatewayEpisodeRunner::run(const EpisodeOptions& options,
                                        const std::atomic<bool>& interrupted) {
  EpisodeReport report;
  report.seed = options.seed;
  const sim::WorldProfile world = served_world(policy_);  // before anything moves
  const sim::WorldParameters& world_parameters = sim::world_parameters(world);
  const geometry::RigidTransform sim_from_base = config_.base_from_sim.inverse();
  const auto deadman = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config_.deadman_timeout_s));
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config_.policy_period_s));

  Eigen::Vector3d goal_base;
  double gripper_command_m = 0;  // held on refusals: keeps a grasp closed
  if (options.reset_scene) {
    const rv1::ResetSceneResponse scene = controller_.reset_scene(options.seed);
    goal_base = services::from_proto(scene.goal());
    gripper_command_m = scene.state().gripper_width_m();
  } else {
    if (!options.goal_base || !options.goal_base->allFinite()) {
      throw_invalid_argument(
          "goal", "a finite goal position (base frame) when the scene is not reset", "none");
    }
    goal_base = *options.goal_base;
    gripper_command_m = controller_.state().state().gripper_width_m();
  }
  const Eigen::Vector3d goal_sim = sim_from_base.apply(goal_base);
  const bool lockstep = controller_.state().lockstep();
  if (!options.dry_run) controller_.open_stream();
  log_("episode_start", {{"seed", options.seed},
                         {"world", sim::world_profile_name(world)},
                         {"goal_sim_m", to_json(goal_sim)},
                         {"lockstep", lockstep},
                         {"dry_run", options.dry_run}});

  PolicySession session(policy_);
  robot::PerceivedObservation perceived;
  bool session_broken = false;
  auto next_cycle = Clock::now();

  auto end_with = [&](EpisodeEnd end, std::string reason) {
    report.end = end;
    report.reason = std::move(reason);
  };

  for (;;) {
    if (interrupted.load()) {
      controller_.stop("gateway interrupted (Ctrl-C)");
      end_with(EpisodeEnd::kInterrupted, "interrupted: the arm was stopped");
      break;
    }
    const auto start = Clock::now();
    const rv1::ControllerFeedback state = controller_.state().state();
    report.state_us.push_back(micros(Clock::now() - start));
    if (state.mode() == rv1::CONTROLLER_MODE_FAULT) {
      end_with(EpisodeEnd::kControllerFault, "the controller reports a fault");
      break;
    }
    const geometry::Pose measured_sim = sim_from_base.apply(services::from_proto(state.measured()));
    const geometry::Pose object_sim =
        sim_from_base.apply(services::from_proto(state.object().pose()));
    if (sim::is_task_success(object_sim.position_m, goal_sim)) {
      report.success = true;
      end_with(EpisodeEnd::kSuccess, "");
      break;
    }
    if (report.steps >= config_.max_episode_steps) break;  // kStepCap

    sim::Observation observation;
    try {
      observation = perceived.update({measured_sim.position_m, state.gripper_width_m(),
                                      object_sim.position_m, object_sim.orientation});
    } catch (const Error& e) {
      // A reading the policy cannot be given: nothing is sent (the arm holds its last
      // target) and the episode ends with the reason; the next episode goes on.
      end_with(EpisodeEnd::kControllerFault, std::string("bad controller reading: ") + e.what());
      log_("bad_reading", {{"step", report.steps}, {"reason", report.reason}});
      break;
    }
    const auto asked = Clock::now();
    std::optional<Prediction> prediction;
    if (session.ask(observation, goal_sim)) prediction = session.answer(asked + deadman);
    report.inference_us.push_back(micros(Clock::now() - asked));
    const geometry::Pose commanded_base = services::from_proto(state.commanded());

    rv1::PoseTarget target;
    target.set_sequence(++sequence_);
    target.set_frame_id(config_.base_frame_id);
    services::to_proto(std::chrono::system_clock::now(), *target.mutable_stamp());
    if (!prediction) {
      session_broken = true;
      const std::string why = "inference did not answer within " +
                              std::to_string(config_.deadman_timeout_s * 1000) + " ms: holding";
      log_("deadman", {{"step", report.steps}, {"reason", why}});
      if (!options.dry_run) {
        services::to_proto(commanded_base, *target.mutable_pose());
        target.set_gripper_width_m(gripper_command_m);
        controller_.send(target);
        controller_.feedback(Clock::now() + deadman);
      }
      end_with(EpisodeEnd::kDeadman, why);
      break;
    }

    const robot::PlannedTarget planned = robot::plan_target(
        config_, world_parameters,
        {commanded_base, services::from_proto(state.measured()), state.gripper_width_m()},
        prediction->action);
    if (planned.verdict.ok()) {
      services::to_proto(planned.base.pose, *target.mutable_pose());
      gripper_command_m = planned.base.gripper_width_m;
      if (planned.rate_limited) ++report.rate_limited;
    } else {
      ++report.refused;
      log_("refused", {{"step", report.steps},
                       {"check", robot::safety_refusal_name(*planned.verdict.refusal)},
                       {"reason", planned.verdict.reason},
                       {"action",
                        {prediction->action(0), prediction->action(1), prediction->action(2),
                         prediction->action(3)}}});
      services::to_proto(commanded_base, *target.mutable_pose());  // hold
    }
    target.set_gripper_width_m(gripper_command_m);

    if (options.dry_run) {
      log_("target", {{"step", report.steps},
                      {"position_base_m", to_json(services::from_proto(target.pose()).position_m)},
                      {"gripper_width_m", target.gripper_width_m()}});
      report.cycle_us.push_back(micros(Clock::now() - start));
    } else {
      const bool sent = controller_.send(target);
      report.cycle_us.push_back(micros(Clock::now() - start));
      const auto feedback = sent ? controller_.feedback(Clock::now() + deadman) : std::nullopt;
      if (!feedback) {
        end_with(EpisodeEnd::kDeadman, "the controller did not answer within " +
                                           std::to_string(config_.deadman_timeout_s * 1000) +
                                           " ms (its own dead-man holds the arm)");
        log_("deadman", {{"step", report.steps}, {"reason", report.reason}});
        break;
      }
      if (feedback->status() != rv1::CONTROLLER_STATUS_OK) {
        ++report.controller_refused;
        log_("controller_refused",
             {{"step", report.steps},
              {"status", rv1::ControllerStatus_Name(feedback->status())},
              {"errors",
               std::vector<std::string>(feedback->errors().begin(), feedback->errors().end())}});
      }
    }
    ++report.steps;
    if (!lockstep) {
      next_cycle += period;
      const auto now = Clock::now();
      if (now > next_cycle) {
        ++report.missed_periods;
        next_cycle = now;
      } else {
        std::this_thread::sleep_until(next_cycle);
      }
    }
  }
  if (!session_broken) session.finish();
  if (!options.dry_run) controller_.close_stream();
  log_("episode_end", {{"seed", options.seed},
                       {"success", report.success},
                       {"end", episode_end_name(report.end)},
                       {"steps", report.steps},
                       {"refused", report.refused},
                       {"controller_refused", report.controller_refused},
                       {"missed_periods", report.missed_periods}});
  return report;
}

}  // namespace pnp::gateway
