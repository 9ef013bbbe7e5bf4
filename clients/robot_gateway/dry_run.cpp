#include "clients/robot_gateway/dry_run.h"

#include <cmath>

#include "common/error.h"
#include "services/common/convert.h"
#include "services/common/robot_convert.h"

namespace pnp::gateway {
namespace {

namespace rv1 = robot::v1;

arm_sim::StandInOptions shadow_options(const policy::v1::ServedRole& served,
                                       const robot::ControllerLimits& live_limits) {
  arm_sim::StandInOptions options;
  options.object = services::from_proto(served.object(), "served object");
  options.world = services::from_proto(served.world(), "served world");
  options.clock = arm_sim::ClockMode::kLockstep;
  options.limits = live_limits;
  return options;
}

std::string metres(double m) {
  return std::to_string(std::round(m * 1e4) / 1e4) + " m";
}

}  // namespace

DryRun::DryRun(const robot::GatewayConfig& config, const robot::ControllerLimits& live_limits,
               ControllerLink& live, policy::v1::PolicyService::Stub& policy, EventLog log,
               bool strict, const std::atomic<bool>& interrupted)
    : config_(config), live_(live), log_(std::move(log)) {
  shadow_ = std::make_unique<arm_sim::ControllerStandIn>(
      shadow_options(served_policy(policy, interrupted), live_limits));
  controller_service_ = std::make_unique<services::RobotControllerServiceImpl>(*shadow_);
  scene_service_ = std::make_unique<services::SimulatedSceneServiceImpl>(*shadow_);
  server_ = std::make_unique<services::ServerRuntime>(
      services::ServerConfig{.address = "127.0.0.1:0",
                             .max_message_bytes = 1 << 20,
                             .services = {controller_service_.get(), scene_service_.get()},
                             .service_names = {},
                             .metrics = nullptr,
                             .metrics_address = {},
                             .security = {},
                             .log_name = "dry_run_shadow"});
  const std::string address = "127.0.0.1:" + std::to_string(server_->port());
  shadow_link_ = std::make_unique<ControllerLink>(
      grpc::CreateChannel(address, grpc::InsecureChannelCredentials()), address,
      std::chrono::milliseconds(2000), interrupted);
  shadow_link_->acquire_lease(live.client_name(), std::chrono::seconds(60));
  runner_ = std::make_unique<GatewayEpisodeRunner>(config_, *shadow_link_, policy, log_, strict);
}

DryRun::~DryRun() {
  runner_.reset();
  shadow_link_.reset();
  server_->shutdown(std::chrono::milliseconds(500));
}

EpisodeReport DryRun::run(const EpisodeOptions& options, const std::atomic<bool>& interrupted) {
  rv1::ControllerFeedback start;
  Eigen::Vector3d goal_base;
  bool live_stopped = false;  // an emergency stop ends the run, as on a live run
  try {
    const rv1::GetStateResponse before = live_.state();
    live_stopped = before.stop_kind() == rv1::STOP_KIND_EMERGENCY;
    if (live_stopped) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "the live arm is emergency-stopped (" + before.stop_reason() +
                      "): an operator must clear it (pnpctl robot resume --ack REASON)");
    }
    if (options.reset_scene) {
      if (before.lease_holder().empty() && live_.has_lease()) live_.reacquire_lease();
      const rv1::ResetSceneResponse scene = live_.reset_scene(options.seed);
      start = scene.state();
      goal_base = services::from_proto(scene.goal());
    } else {
      if (!options.goal_base || !options.goal_base->allFinite()) {
        throw_invalid_argument(
            "goal", "a finite goal position (base frame) when the scene is not reset", "none");
      }
      start = live_.state().state();
      goal_base = *options.goal_base;
    }
    if (start.mode() == rv1::CONTROLLER_MODE_STOPPED || start.mode() == rv1::CONTROLLER_MODE_FAULT)
      throw Error(ErrorCode::kFailedPrecondition, "the live arm is stopped or faulted");
    if (!start.has_object())
      throw Error(ErrorCode::kFailedPrecondition, "the live controller perceives no object");
    if (shadow_link_->state().lease_holder().empty()) shadow_link_->reacquire_lease();
    shadow_->reset_scene_to(shadow_link_->lease_id(),
                            {services::from_proto(start.measured()), start.gripper_width_m(),
                             services::from_proto(start.object().pose()), goal_base});
  } catch (const Error& e) {
    EpisodeReport report;
    report.seed = options.seed;
    report.end = interrupted.load() ? EpisodeEnd::kInterrupted
                 : live_stopped     ? EpisodeEnd::kStopped
                                    : EpisodeEnd::kControllerFault;
    report.reason =
        std::string("dry run: the shadow could not start where the live arm is: ") + e.what();
    report.arm_left = "untouched (dry run)";
    log_("episode_end", {{"seed", options.seed},
                         {"success", false},
                         {"end", episode_end_name(report.end)},
                         {"reason", report.reason},
                         {"arm_left", report.arm_left},
                         {"steps", 0}});
    return report;
  }
  EpisodeOptions shadow = options;
  shadow.reset_scene = false;
  shadow.goal_base = goal_base;
  shadow.watch = [this, start] { return watch_live(start); };
  EpisodeReport report = runner_->run(shadow, interrupted);
  report.arm_left = "untouched (dry run)";
  return report;
}

// The live arm must hold, and the object stay, while the shadow plays.
std::optional<WatchVerdict> DryRun::watch_live(const rv1::ControllerFeedback& start) {
  const auto deadman = config_.deadman_timeout();
  const auto now = live_.state(deadman);
  if (!now) {
    return WatchVerdict{EpisodeEnd::kDeadman,
                        "dry run: the live controller did not answer GetState within " +
                            std::to_string(deadman.count()) + " ms"};
  }
  const rv1::ControllerFeedback& live = now->state();
  if (live.mode() == rv1::CONTROLLER_MODE_STOPPED) {
    return WatchVerdict{EpisodeEnd::kStopped, "dry run: the live arm was stopped (" +
                                                  rv1::StopKind_Name(now->stop_kind()) + ": " +
                                                  now->stop_reason() + ")"};
  }
  if (live.mode() == rv1::CONTROLLER_MODE_FAULT)
    return WatchVerdict{EpisodeEnd::kControllerFault,
                        "dry run: the live controller reports a fault"};
  const double arm_drift = (services::from_proto(live.measured()).position_m -
                            services::from_proto(start.measured()).position_m)
                               .norm();
  if (!(arm_drift <= kDryRunDrift_m)) {
    return WatchVerdict{EpisodeEnd::kControllerFault,
                        "dry run: the live arm moved " + metres(arm_drift) +
                            " while the shadow played (it must hold)"};
  }
  if (!live.has_object()) {
    return WatchVerdict{EpisodeEnd::kControllerFault,
                        "dry run: the live controller no longer perceives the object"};
  }
  const double object_drift = (services::from_proto(live.object().pose()).position_m -
                               services::from_proto(start.object().pose()).position_m)
                                  .norm();
  if (!(object_drift <= kDryRunDrift_m)) {
    return WatchVerdict{
        EpisodeEnd::kControllerFault,
        "dry run: the object moved " + metres(object_drift) + " while the shadow played"};
  }
  return std::nullopt;
}

}  // namespace pnp::gateway
