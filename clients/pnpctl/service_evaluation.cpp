#include "clients/pnpctl/service_evaluation.h"

#include <algorithm>
#include <map>

#include "clients/pnpctl/rpc.h"
#include "common/error.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"

namespace pnp::pnpctl {
namespace {

char subtask_letter(common::v1::Subtask subtask) {
  switch (subtask) {
    case common::v1::SUBTASK_APPROACH:
      return 'A';
    case common::v1::SUBTASK_MANIPULATE:
      return 'M';
    case common::v1::SUBTASK_RETRACT:
      return 'R';
    default:
      return '?';
  }
}

struct EpisodeOutcome {
  bool success = false;
  int steps = 0;
  std::string choices;
};

// One episode: reset on the simulation service, then alternately ask the session for the
// next action and step the environment with it, until the episode is over.
EpisodeOutcome run_episode(sim::v1::SimulationService::Stub& sim,
                           policy::v1::PolicyService::Stub& policy, const Endpoints& endpoints,
                           const std::string& env_id, int episode_steps) {
  sim::v1::ResetRequest reset;
  reset.set_env_id(env_id);
  sim::v1::ResetResponse reset_response;
  check(sim.Reset(context_with_deadline().get(), reset, &reset_response), "Reset", endpoints.sim);
  sim::v1::EnvState state = reset_response.states(0);

  grpc::ClientContext session_context;
  auto session = policy.PredictSession(&session_context);
  EpisodeOutcome out;
  for (;;) {
    policy::v1::PredictSessionRequest ask;
    *ask.mutable_observation() = state.observation();
    *ask.mutable_goal() = state.episode_goal();
    ask.set_episode_steps(episode_steps);
    policy::v1::PredictSessionResponse answer;
    if (!session->Write(ask) || !session->Read(&answer)) break;
    if (answer.decided()) out.choices += subtask_letter(answer.prediction().subtask());
    sim::v1::StepRequest step;
    step.set_env_id(env_id);
    auto& action = *step.add_actions();
    action.set_index(0);
    *action.mutable_action() = answer.prediction().action();
    *action.mutable_goal() = state.episode_goal();
    action.set_objective(sim::v1::OBJECTIVE_TASK);
    sim::v1::StepResponse stepped;
    check(sim.Step(context_with_deadline().get(), step, &stepped), "Step", endpoints.sim);
    const auto& result = stepped.results(0);
    ++out.steps;
    state = result.state();
    if (result.episode_over()) {
      out.success = result.task_success();
      break;
    }
  }
  session->WritesDone();
  check(session->Finish(), "PredictSession", endpoints.inference);
  return out;
}

// Closes the environment on every way out (it would otherwise linger until its idle
// timeout).
class EnvLease {
 public:
  EnvLease(sim::v1::SimulationService::Stub& sim, std::string id) : sim_(sim), id_(std::move(id)) {}
  ~EnvLease() {
    sim::v1::CloseEnvRequest close;
    close.set_env_id(id_);
    sim::v1::CloseEnvResponse closed;
    sim_.CloseEnv(context_with_deadline(std::chrono::seconds(2)).get(), close, &closed);
  }
  EnvLease(const EnvLease&) = delete;
  EnvLease& operator=(const EnvLease&) = delete;
  const std::string& id() const { return id_; }

 private:
  sim::v1::SimulationService::Stub& sim_;
  std::string id_;
};

}  // namespace

void require_evaluation_episodes(int episodes) {
  if (episodes <= 0)
    throw_invalid_argument("--episodes", "a positive integer", std::to_string(episodes));
}

ServiceEvaluation evaluate_through_services(const Endpoints& endpoints, const ServiceWorld& world,
                                            int episodes, std::uint64_t seed) {
  require_evaluation_episodes(episodes);
  auto sim = sim::v1::SimulationService::NewStub(endpoints.channel(endpoints.sim));
  auto policy = policy::v1::PolicyService::NewStub(endpoints.channel(endpoints.inference));
  sim::v1::CreateEnvRequest create;
  create.set_robot(world.robot);
  create.set_object(world.object);
  create.set_world(world.world);
  create.set_actuation(world.actuation);
  create.set_seed(seed);
  create.set_count(1);
  sim::v1::CreateEnvResponse created;
  check(sim->CreateEnv(context_with_deadline().get(), create, &created), "CreateEnv",
        endpoints.sim);
  const EnvLease env(*sim, created.env_id());
  ServiceEvaluation out;
  std::map<std::string, int> sequences;
  for (int i = 0; i < episodes; ++i) {
    const EpisodeOutcome e =
        run_episode(*sim, *policy, endpoints, env.id(), created.episode_steps());
    ++out.episodes;
    out.successes += e.success ? 1 : 0;
    out.env_steps += e.steps;
    ++sequences[e.choices];
  }
  out.sequences.assign(sequences.begin(), sequences.end());
  std::sort(out.sequences.begin(), out.sequences.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  return out;
}

}  // namespace pnp::pnpctl
