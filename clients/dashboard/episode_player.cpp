#include "clients/dashboard/episode_player.h"

#include <chrono>

#include "common/error.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "services/common/convert.h"
#include "services/common/status.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_layout.h"
#include "sim/world_profile.h"

namespace pnp::dashboard {
namespace {

namespace sv1 = pnp::sim::v1;
namespace pv1 = pnp::policy::v1;

std::unique_ptr<grpc::ClientContext> with_deadline() {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  return context;
}

plot::EpisodeFrame frame_of(const sv1::EnvState& state, int subtask) {
  const auto& v = state.observation().values();
  plot::EpisodeFrame f;
  f.subtask = subtask;
  if (v.size() >= 6) {
    f.gripper = {v[0], v[1], v[2]};
    f.object = {v[3], v[4], v[5]};
  }
  return f;
}

// Closes the environment on every way out.
class EnvLease {
 public:
  EnvLease(sv1::SimulationService::Stub& sim, std::string id) : sim_(sim), id_(std::move(id)) {}
  ~EnvLease() {
    sv1::CloseEnvRequest close;
    close.set_env_id(id_);
    sv1::CloseEnvResponse closed;
    sim_.CloseEnv(with_deadline().get(), close, &closed);
  }
  EnvLease(const EnvLease&) = delete;
  EnvLease& operator=(const EnvLease&) = delete;
  const std::string& id() const { return id_; }

 private:
  sv1::SimulationService::Stub& sim_;
  std::string id_;
};

plot::EpisodeTrace play_one(sv1::SimulationService::Stub& sim, pv1::PolicyService::Stub& policy,
                            const std::string& env_id, int episode_steps,
                            const std::string& title) {
  sv1::ResetRequest reset;
  reset.set_env_id(env_id);
  sv1::ResetResponse reset_response;
  services::throw_if_error(sim.Reset(with_deadline().get(), reset, &reset_response), "Reset",
                           "the simulation service");
  sv1::EnvState state = reset_response.states(0);
  plot::EpisodeTrace trace;
  trace.title = title;
  trace.goal = {state.episode_goal().x_m(), state.episode_goal().y_m(), state.episode_goal().z_m()};
  trace.success_radius_m = sim::layout::kTaskSuccessDistance;
  trace.table_top_z = sim::layout::kTableTop_z;
  trace.frames.push_back(frame_of(state, -1));
  // A whole episode is 50 or 75 answers: a hung inference service frees this worker after a
  // minute instead of holding it forever.
  grpc::ClientContext session_context;
  session_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto session = policy.PredictSession(&session_context);
  for (;;) {
    pv1::PredictSessionRequest ask;
    *ask.mutable_observation() = state.observation();
    *ask.mutable_goal() = state.episode_goal();
    ask.set_episode_steps(episode_steps);
    pv1::PredictSessionResponse answer;
    if (!session->Write(ask) || !session->Read(&answer)) break;
    sv1::StepRequest step;
    step.set_env_id(env_id);
    auto& action = *step.add_actions();
    *action.mutable_action() = answer.prediction().action();
    *action.mutable_goal() = state.episode_goal();
    action.set_objective(sv1::OBJECTIVE_TASK);
    sv1::StepResponse stepped;
    services::throw_if_error(sim.Step(with_deadline().get(), step, &stepped), "Step",
                             "the simulation service");
    const auto& result = stepped.results(0);
    state = result.state();
    trace.frames.push_back(frame_of(state, services::subtask_index(answer.prediction().subtask())));
    if (result.episode_over()) {
      trace.success = result.task_success();
      break;
    }
  }
  session->WritesDone();
  services::throw_if_error(session->Finish(), "PredictSession", "the inference service");
  return trace;
}

}  // namespace

EpisodePlayer::EpisodePlayer(std::shared_ptr<grpc::Channel> sim,
                             std::shared_ptr<grpc::Channel> inference)
    : sim_(std::move(sim)), inference_(std::move(inference)) {}

ServedWorld EpisodePlayer::served_world() {
  auto policy = pv1::PolicyService::NewStub(inference_);
  pv1::GetServingStatusResponse status;
  services::throw_if_error(policy->GetServingStatus(with_deadline().get(), {}, &status),
                           "GetServingStatus", "the inference service");
  if (!status.ready())
    throw Error(ErrorCode::kFailedPrecondition,
                "the inference service serves no hierarchy yet (promote one: pnpctl promote)");
  ServedWorld out;
  // The choreographer's world; an end-to-end policy's when that is what is served.
  for (const auto& role : status.roles()) {
    const bool defines_world =
        role.role() == common::v1::ROLE_HLC || role.role() == common::v1::ROLE_E2E;
    if (!defines_world || role.robot() == common::v1::ROBOT_UNSPECIFIED) continue;
    out.robot = sim::robot_name(services::from_proto(role.robot(), "robot"));
    out.object = sim::object_name(services::from_proto(role.object(), "object"));
    out.world = sim::world_profile_name(services::from_proto(role.world(), "world"));
    // Unset: a server from before the actuation was kept (its policies were mocap-trained).
    out.actuation =
        sim::actuation_name(role.actuation() == common::v1::ACTUATION_ARM ? sim::Actuation::kArm
                                                                          : sim::Actuation::kMocap);
  }
  return out;
}

PlayedEpisodes EpisodePlayer::play(int count, std::uint64_t seed) {
  if (count < 1 || count > kMaxEpisodes)
    throw_invalid_argument("count", "1 to " + std::to_string(kMaxEpisodes) + " episodes",
                           std::to_string(count));
  PlayedEpisodes out;
  out.world = served_world();
  out.seed = seed;
  auto sim = sv1::SimulationService::NewStub(sim_);
  auto policy = pv1::PolicyService::NewStub(inference_);
  sv1::CreateEnvRequest create;
  create.set_robot(services::to_proto(sim::parse_robot(out.world.robot)));
  create.set_object(services::to_proto(sim::parse_object(out.world.object)));
  create.set_world(services::to_proto(sim::parse_world_profile(out.world.world)));
  create.set_actuation(services::to_proto(sim::parse_actuation(out.world.actuation)));
  create.set_seed(seed);
  create.set_count(1);
  sv1::CreateEnvResponse created;
  services::throw_if_error(sim->CreateEnv(with_deadline().get(), create, &created), "CreateEnv",
                           "the simulation service");
  const EnvLease env(*sim, created.env_id());
  for (int i = 0; i < count; ++i) {
    out.episodes.push_back(
        play_one(*sim, *policy, env.id(), created.episode_steps(),
                 "episode " + std::to_string(i) + " of seed " + std::to_string(seed)));
    out.successes += out.episodes.back().success ? 1 : 0;
  }
  return out;
}

}  // namespace pnp::dashboard
