// promote, predict, health and evaluate: the inference side and the platform's health.
#include <algorithm>
#include <nlohmann/json.hpp>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/service_evaluation.h"
#include "clients/pnpctl/table.h"
#include "common/error.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "services/common/convert.h"
#include "services/common/status.h"

namespace pnp::pnpctl {

int promote_command(const Endpoints& endpoints, const std::vector<std::int64_t>& checkpoint_ids) {
  auto stub = policy::v1::PolicyService::NewStub(endpoints.channel(endpoints.inference));
  policy::v1::PromoteCheckpointRequest request;
  for (const std::int64_t id : checkpoint_ids) request.add_checkpoint_ids(id);
  policy::v1::PromoteCheckpointResponse response;
  check(stub->PromoteCheckpoint(context_with_deadline().get(), request, &response),
        "PromoteCheckpoint", endpoints.inference);
  for (const auto& p : response.promoted()) {
    std::printf("checkpoint %lld now serves %s (run %lld, %lld training steps, %s)\n",
                static_cast<long long>(p.checkpoint_id()), short_name(p.role()).c_str(),
                static_cast<long long>(p.run_id()), static_cast<long long>(p.env_steps()),
                p.latest_of_run() ? "the run's latest checkpoint"
                                  : "NOT the run's latest: an intermediate model");
  }
  return 0;
}

int promote_runs_command(const Endpoints& endpoints, const std::vector<std::int64_t>& run_ids,
                         const std::string& via) {
  const std::string& address = endpoints.training(via);
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  std::vector<std::int64_t> checkpoint_ids;
  for (const std::int64_t run_id : run_ids) {
    train::v1::GetTrainingRunRequest request;
    request.set_run_id(run_id);
    train::v1::GetTrainingRunResponse response;
    check(stub->GetTrainingRun(context_with_deadline().get(), request, &response), "GetTrainingRun",
          address);
    if (response.run().latest_checkpoint_id() == 0) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "--run " + std::to_string(run_id) + ": the run has no checkpoint yet");
    }
    checkpoint_ids.push_back(response.run().latest_checkpoint_id());
  }
  return promote_command(endpoints, checkpoint_ids);
}

namespace {

// The first observation and goal of the simulation service's episode for `seed`.
void observe_from_sim(const Endpoints& endpoints, const PredictArgs& args,
                      policy::v1::PredictRequest& request) {
  auto sim = sim::v1::SimulationService::NewStub(endpoints.channel(endpoints.sim));
  sim::v1::CreateEnvRequest create;
  create.set_robot(parse_robot(args.robot, "--robot"));
  create.set_object(parse_object(args.object, "--object"));
  create.set_world(parse_world(args.world, "--world"));
  create.set_actuation(parse_actuation(args.actuation, args.robot, "--actuation"));
  create.set_seed(args.seed);
  create.set_count(1);
  sim::v1::CreateEnvResponse created;
  check(sim->CreateEnv(context_with_deadline().get(), create, &created), "CreateEnv",
        endpoints.sim);
  sim::v1::ResetRequest reset;
  reset.set_env_id(created.env_id());
  sim::v1::ResetResponse state;
  const grpc::Status status = sim->Reset(context_with_deadline().get(), reset, &state);
  sim::v1::CloseEnvRequest close;
  close.set_env_id(created.env_id());
  sim::v1::CloseEnvResponse closed;
  sim->CloseEnv(context_with_deadline().get(), close, &closed);
  check(status, "Reset", endpoints.sim);
  *request.mutable_observation() = state.states(0).observation();
  *request.mutable_goal() = state.states(0).episode_goal();
}

}  // namespace

int predict_command(const Endpoints& endpoints, const PredictArgs& args) {
  policy::v1::PredictRequest request;
  if (args.observation.empty() && args.goal.empty()) {
    observe_from_sim(endpoints, args, request);
  } else {
    // Sizes are checked by the service, which names the field; only the goal's three
    // components are placed here.
    for (double v : args.observation) request.mutable_observation()->add_values(v);
    if (args.goal.size() != 3)
      throw_invalid_argument("--goal", "3 comma-separated values (x,y,z in m)",
                             std::to_string(args.goal.size()) + " values");
    request.mutable_goal()->set_x_m(args.goal[0]);
    request.mutable_goal()->set_y_m(args.goal[1]);
    request.mutable_goal()->set_z_m(args.goal[2]);
  }
  auto stub = policy::v1::PolicyService::NewStub(endpoints.channel(endpoints.inference));
  policy::v1::PredictResponse response;
  check(stub->Predict(context_with_deadline().get(), request, &response), "Predict",
        endpoints.inference);
  const auto& a = response.action();
  std::printf("subtask  %s\naction   dx %+.3f  dy %+.3f  dz %+.3f  gripper %+.3f\nvalue    %.4f\n",
              short_name(response.subtask()).c_str(), a.dx(), a.dy(), a.dz(), a.gripper(),
              response.value());
  if (response.subtask_probabilities_size() == 3) {
    std::printf("choice   approach %.3f  manipulate %.3f  retract %.3f\n",
                response.subtask_probabilities(0), response.subtask_probabilities(1),
                response.subtask_probabilities(2));
  }
  std::printf("served   choreographer checkpoint %lld, expert checkpoint %lld\n",
              static_cast<long long>(response.choreographer_checkpoint_id()),
              static_cast<long long>(response.expert_checkpoint_id()));
  return 0;
}

int health_command(const Endpoints& endpoints, const std::vector<std::string>& services,
                   double timeout_s, const std::vector<std::string>& optional) {
  Table table({"service", "address", "status"});
  int failures = 0;
  std::vector<std::string> hints;
  for (const auto& name : services) {
    const std::string& address = endpoints.address_of(name);
    auto stub = grpc::health::v1::Health::NewStub(endpoints.channel(address));
    grpc::health::v1::HealthCheckResponse response;
    const auto timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000));
    const grpc::Status status = stub->Check(context_with_deadline(timeout).get(), {}, &response);
    std::string text;
    if (!status.ok()) {
      text = status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                     status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED
                 ? "UNREACHABLE"
                 : "ERROR: " + status.error_message();
      const std::string hint = services::transport_hint(status);
      if (!hint.empty()) hints.push_back(name + ": " + hint);
    } else {
      text = grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
    }
    const bool may_be_down = std::find(optional.begin(), optional.end(), name) != optional.end();
    if (text != "SERVING" && may_be_down) {
      text += " (optional)";
    } else if (text != "SERVING") {
      ++failures;
    }
    table.add({name, address, text});
  }
  table.print(stdout);
  for (const auto& hint : hints) std::fprintf(stderr, "pnpctl: %s\n", hint.c_str());
  if (failures > 0 && !endpoints.endpoints_file.empty())
    std::fprintf(
        stderr, "%s\n",
        with_endpoints_hint(endpoints, "pnpctl: health: a service is not serving").c_str());
  return failures == 0 ? 0 : 1;
}

namespace {

// The served roles trained on another world than the one to evaluate on, as "hlc
// (gym/fetch/block, mocap hand)"; empty if none. A mismatch can be deliberate (a retract
// fine-tuned for another shape), so it is a warning unless --strict.
std::string served_world_mismatch(const Endpoints& endpoints, const EvaluateArgs& args,
                                  const std::string& actuation) {
  auto stub = policy::v1::PolicyService::NewStub(endpoints.channel(endpoints.inference));
  policy::v1::GetServingStatusResponse status;
  check(stub->GetServingStatus(context_with_deadline().get(), {}, &status), "GetServingStatus",
        endpoints.inference);
  std::string out;
  for (const auto& r : status.roles()) {
    if (r.robot() == common::v1::ROBOT_UNSPECIFIED) continue;  // not recorded
    const std::string served_robot(sim::robot_name(services::from_proto(r.robot(), "robot")));
    const std::string served_object(sim::object_name(services::from_proto(r.object(), "object")));
    const std::string served_world(
        sim::world_profile_name(services::from_proto(r.world(), "world")));
    // Unset: a server from before the actuation was kept (its policies were mocap-trained).
    const std::string served_actuation(
        sim::actuation_name(r.actuation() == common::v1::ACTUATION_ARM ? sim::Actuation::kArm
                                                                       : sim::Actuation::kMocap));
    if (served_robot == args.robot && served_object == args.object && served_world == args.world &&
        served_actuation == actuation)
      continue;
    out += (out.empty() ? "" : ", ") + short_name(r.role()) + " (" + served_world + "/" +
           served_robot + "/" + served_object + ", " + served_actuation + " hand)";
  }
  return out;
}

}  // namespace

int evaluate_command(const Endpoints& endpoints, const EvaluateArgs& args) {
  // Bad input is refused before any service is asked.
  const ServiceWorld world{parse_robot(args.robot, "--robot"),
                           parse_object(args.object, "--object"),
                           parse_world(args.world, "--world"),
                           parse_actuation(args.actuation, args.robot, "--actuation")};
  require_evaluation_episodes(args.episodes);
  const std::string actuation(
      sim::actuation_name(resolve_actuation(args.actuation, args.robot, "--actuation")));
  const std::string where =
      args.world + "/" + args.robot + "/" + args.object + " (" + actuation + " hand)";
  if (const std::string mismatch = served_world_mismatch(endpoints, args, actuation);
      !mismatch.empty()) {
    const std::string message =
        "evaluating on " + where + ", but the served policy was trained elsewhere: " + mismatch;
    if (args.strict) throw Error(ErrorCode::kFailedPrecondition, message);
    std::fprintf(stderr, "pnpctl: warning: %s\n", message.c_str());
  }
  const std::uint64_t seed = args.seed;
  const ServiceEvaluation e = evaluate_through_services(endpoints, world, args.episodes, seed);
  if (args.json) {
    nlohmann::json out = {{"episodes", e.episodes},
                          {"successes", e.successes},
                          {"success_rate", e.success_rate()},
                          {"env_steps", e.env_steps},
                          {"seed", seed},
                          {"sequences", e.sequences}};
    std::printf("%s\n", out.dump().c_str());
    return 0;
  }
  std::printf("%s: success %.3f over %d held-out episodes (seed %llu)", where.c_str(),
              e.success_rate(), e.episodes, static_cast<unsigned long long>(seed));
  if (!e.sequences.empty())
    std::printf(", most frequent choices %s x%d", e.sequences.front().first.c_str(),
                e.sequences.front().second);
  std::printf("\n");
  return 0;
}

}  // namespace pnp::pnpctl
