#include "clients/sim_client/remote_environment.h"

#include "common/error.h"
#include "services/common/convert.h"
#include "services/common/sim_convert.h"
#include "services/common/status.h"
#include "sim/step_rules.h"

namespace pnp::sim_client {

namespace sv1 = pnp::sim::v1;

RemoteEnvironment::RemoteEnvironment(std::shared_ptr<grpc::Channel> channel, std::string address,
                                     sim::Robot robot, sim::ObjectShape object,
                                     sim::WorldProfile world, sim::Actuation actuation,
                                     std::chrono::milliseconds connect_timeout)
    : stub_(sv1::SimulationService::NewStub(channel)),
      address_(std::move(address)),
      object_width_m_(2 * sim::object_spec(object).half_width_m),
      episode_steps_(sim::episode_steps(actuation)) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + connect_timeout);
  context.set_wait_for_ready(true);  // a service still starting is waited for, up to the deadline
  sv1::CreateEnvRequest create;
  create.set_robot(services::to_proto(robot));
  create.set_object(services::to_proto(object));
  create.set_world(services::to_proto(world));
  create.set_actuation(services::to_proto(actuation));
  create.set_count(1);
  // The longest idle time allowed: a trainer may pause between uses (updates, evaluations).
  create.mutable_idle_timeout()->set_seconds(3600);
  sv1::CreateEnvResponse created;
  services::throw_if_error(stub_->CreateEnv(&context, create, &created),
                           "simulation service CreateEnv", address_);
  env_id_ = created.env_id();
  stream_ = stub_->StreamRollout(&stream_context_);
  request_.set_env_id(env_id_);
  if (!stream_->Write(request_)) fail("simulation service StreamRollout", stream_->Finish());
}

RemoteEnvironment::~RemoteEnvironment() {
  if (stream_) {
    if (!broken_) {
      stream_->WritesDone();
      stream_->Finish();
    } else {
      stream_context_.TryCancel();
    }
  }
  // Best effort: a batch left behind expires on the service anyway.
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  sv1::CloseEnvRequest close;
  close.set_env_id(env_id_);
  sv1::CloseEnvResponse closed;
  stub_->CloseEnv(&context, close, &closed);
}

void RemoteEnvironment::fail(const std::string& what, const grpc::Status& status) {
  broken_ = true;
  services::throw_if_error(
      status.ok() ? grpc::Status(grpc::StatusCode::UNAVAILABLE, "the stream ended") : status, what,
      address_);
  throw Error(ErrorCode::kInternal, "unreachable");  // throw_if_error threw
}

void RemoteEnvironment::exchange() {
  if (broken_) {
    throw Error(ErrorCode::kUnavailable,
                "simulation service (" + address_ + "): the rollout stream failed earlier");
  }
  if (!stream_->Write(request_) || !stream_->Read(&response_)) {
    fail("simulation service StreamRollout", stream_->Finish());
  }
}

void RemoteEnvironment::take(const sv1::EnvState& state) {
  observation_ = services::from_proto(state.observation(), "observation");
  episode_goal_ = services::from_proto(state.episode_goal(), "episode_goal");
  elapsed_steps_ = state.elapsed_steps();
  // A fault restarts the episode on the service (elapsed 0), as PickPlaceEnv does.
  needs_reset_ = elapsed_steps_ >= episode_steps_;
}

const sim::Observation& RemoteEnvironment::reset(std::uint64_t seed) {
  request_.Clear();
  auto& reset = *request_.mutable_reset();
  reset.set_env_id(env_id_);
  reset.add_episode_seeds(seed);
  exchange();
  if (!response_.has_reset() || response_.reset().states_size() != 1) {
    fail("simulation service Reset",
         {grpc::StatusCode::INTERNAL, "expected the state of one environment"});
  }
  take(response_.reset().states(0));
  return observation_;
}

sim::StepResult RemoteEnvironment::step(std::span<const double> action,
                                        std::span<const double> goal, sim::Objective objective) {
  sim::require_steppable(action, goal, needs_reset_, elapsed_steps_);
  request_.Clear();
  auto& step = *request_.mutable_step();
  step.set_env_id(env_id_);
  auto& a = *step.add_actions();
  a.set_index(0);
  services::to_proto(sim::Action(action[0], action[1], action[2], action[3]), *a.mutable_action());
  services::to_proto(Eigen::Vector3d(goal[0], goal[1], goal[2]), *a.mutable_goal());
  a.set_objective(services::to_proto(objective));
  exchange();
  if (!response_.has_step() || response_.step().results_size() != 1) {
    fail("simulation service Step",
         {grpc::StatusCode::INTERNAL, "expected the result of one environment"});
  }
  const sv1::StepResult& r = response_.step().results(0);
  take(r.state());
  sim::StepResult out;
  out.observation = observation_;
  out.achieved_goal = sim::achieved_goal(objective, task_state());
  out.reward = r.reward();
  out.task_success = r.task_success();
  out.objective_done = r.objective_done();
  out.episode_over = r.episode_over();
  out.fault = services::from_proto(r.fault(), "fault");
  return out;
}

sim::TaskState RemoteEnvironment::task_state() const {
  return sim::TaskState::from(observation_, episode_goal_, object_width_m_);
}

}  // namespace pnp::sim_client
