// pipeline: the paper's method through the platform. The three experts are trained in
// order, each after the learned experts before it (chained, docs/LEARNING.md) where the
// preset says so and after scripted ones otherwise (on the arm-actuated world backward:
// retract first, each judged with the learned experts after it), then the
// choreographer over them; the four final checkpoints are promoted together; the served hierarchy
// is evaluated on held-out episodes through the simulation and inference services.
#include <array>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/expected_results.h"
#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/run_display.h"
#include "clients/pnpctl/run_watch.h"
#include "clients/pnpctl/service_evaluation.h"
#include "clients/pnpctl/table.h"
#include "common/error.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "training/preset.h"

namespace pnp::pnpctl {
namespace {

using Clock = std::chrono::steady_clock;

// Waits until every service answers SERVING, or throws UNAVAILABLE naming the first that
// does not after `wait_s`.
void wait_until_healthy(const Endpoints& endpoints, const std::vector<std::string>& services,
                        double wait_s) {
  const auto deadline =
      Clock::now() + std::chrono::milliseconds(static_cast<long long>(wait_s * 1000));
  for (const auto& name : services) {
    const std::string& address = endpoints.address_of(name);
    auto stub = grpc::health::v1::Health::NewStub(endpoints.channel(address));
    for (;;) {
      grpc::health::v1::HealthCheckResponse response;
      const grpc::Status status =
          stub->Check(context_with_deadline(std::chrono::seconds(1)).get(), {}, &response);
      if (status.ok() && response.status() == grpc::health::v1::HealthCheckResponse::SERVING) break;
      if (Clock::now() > deadline) {
        throw Error(ErrorCode::kUnavailable, "the " + name + " service (" + address +
                                                 ") is not serving: " + status.error_message());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
}

struct RoleResult {
  train::v1::TrainingRun run;
  double wall_s = 0;  // training and its evaluations, from the run's learning curve
};

RoleResult train(const Endpoints& endpoints, const TrainArgs& args) {
  const std::string& address = endpoints.training(args.role);
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  train::v1::CreateTrainingRunResponse created;
  check(stub->CreateTrainingRun(context_with_deadline().get(), make_request(args), &created),
        "CreateTrainingRun", address);
  RoleResult out;
  out.run = watch_run(endpoints, address, created.run().run_id(), {args.quiet, stderr});
  if (out.run.state() != train::v1::RUN_STATE_SUCCEEDED) {
    throw Error(ErrorCode::kFailedPrecondition,
                args.role + " run " + std::to_string(out.run.run_id()) + " ended " +
                    short_name(out.run.state()) + ": " + out.run.error());
  }
  train::v1::GetRunMetricsRequest metrics_request;
  metrics_request.set_run_id(out.run.run_id());
  train::v1::GetRunMetricsResponse metrics;
  check(stub->GetRunMetrics(context_with_deadline().get(), metrics_request, &metrics),
        "GetRunMetrics", address);
  if (metrics.points_size() > 0) out.wall_s = metrics.points(metrics.points_size() - 1).wall_s();
  return out;
}

// The inference service serves a promotion at once; this waits for the choreographer's
// to be the one served (a reload by another writer could lag by its reload period).
void wait_until_served(const Endpoints& endpoints, std::int64_t hlc_checkpoint, double wait_s) {
  auto stub = policy::v1::PolicyService::NewStub(endpoints.channel(endpoints.inference));
  const auto deadline =
      Clock::now() + std::chrono::milliseconds(static_cast<long long>(wait_s * 1000));
  for (;;) {
    policy::v1::GetServingStatusResponse status;
    check(stub->GetServingStatus(context_with_deadline().get(), {}, &status), "GetServingStatus",
          endpoints.inference);
    for (const auto& role : status.roles())
      if (status.ready() && role.role() == common::v1::ROLE_HLC &&
          role.checkpoint_id() == hlc_checkpoint)
        return;
    if (Clock::now() > deadline)
      throw Error(ErrorCode::kUnavailable, "the inference service did not serve checkpoint " +
                                               std::to_string(hlc_checkpoint));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

}  // namespace

int pipeline_command(const Endpoints& endpoints, const PipelineArgs& args) {
  // Checked before anything trains; printed as resolved ("default" is the robot's own).
  const std::string actuation(sim::actuation_name(
      resolve_actuation(args.experts.actuation, args.experts.robot, "--actuation")));
  wait_until_healthy(endpoints, {"sim", "approach", "manipulate", "retract", "hlc", "inference"},
                     args.wait_s);
  std::vector<RoleResult> results;
  // Forward chaining: each expert after the learned ones before it; backward (the arm
  // world): each judged with the learned ones after it; or every other one scripted.
  const training::ExpertOrder order = training::expert_order(
      training::find_preset(args.experts.preset, "--preset"),
      resolve_actuation(args.experts.actuation, args.experts.robot, "--actuation"));
  std::array<std::int64_t, sim::kNumSubtasks> trained{};
  for (const sim::Subtask subtask : training::training_order(order)) {
    const auto k = static_cast<std::size_t>(subtask);
    TrainArgs a = args.experts;
    a.role = std::string(sim::subtask_name(subtask));
    for (std::size_t other = 0; other < trained.size(); ++other) {
      if (order == training::ExpertOrder::kForward && other < k) a.prefix.push_back(trained[other]);
      if (order == training::ExpertOrder::kBackward && other > k)
        a.successors.push_back(trained[other]);
    }
    results.push_back(train(endpoints, a));
    trained[k] = results.back().run.latest_checkpoint_id();
  }
  const std::vector<std::int64_t> experts(trained.begin(), trained.end());
  TrainArgs hlc = args.choreographer;
  hlc.role = "hlc";
  hlc.experts = experts;
  results.push_back(train(endpoints, hlc));
  // The four together, in one transaction: the inference service never serves new experts
  // under an old choreographer.
  const std::vector<std::int64_t> hierarchy{trained[0], trained[1], trained[2],
                                            results.back().run.latest_checkpoint_id()};
  promote_command(endpoints, hierarchy);
  wait_until_served(endpoints, results.back().run.latest_checkpoint_id(), args.wait_s);
  const ServiceEvaluation held_out = evaluate_through_services(
      endpoints,
      {parse_robot(args.experts.robot, "--robot"), parse_object(args.experts.object, "--object"),
       parse_world(args.experts.world, "--world"),
       parse_actuation(args.experts.actuation, args.experts.robot, "--actuation")},
      args.eval_episodes, args.eval_seed);

  Table table({"role", "run", "state", "steps", "to_target", "score", "target", "final_success",
               "wall", "checkpoint"});
  long long total_steps = 0;
  double total_wall = 0;
  int not_reached = 0;
  nlohmann::json json_roles = nlohmann::json::array();
  for (const auto& r : results) {
    const auto& run = r.run;
    // Steps the part needed: to its target if reached, everything it spent otherwise.
    const long long steps = run.reached() ? run.steps_to_target() : run.env_steps();
    total_steps += steps;
    total_wall += r.wall_s;
    not_reached += run.reached() ? 0 : 1;
    table.add({short_name(run.role()), std::to_string(run.run_id()), outcome_text(run),
               std::to_string(run.env_steps()),
               run.reached() ? std::to_string(run.steps_to_target()) : "not reached",
               score_text(run), fixed(run.target_success(), 2), fixed(run.last_success(), 2),
               fixed(r.wall_s, 1) + " s", std::to_string(run.latest_checkpoint_id())});
    json_roles.push_back({{"role", short_name(run.role())},
                          {"run_id", run.run_id()},
                          {"env_steps", run.env_steps()},
                          {"reached", run.reached()},
                          {"steps_to_target", run.reached() ? nlohmann::json(run.steps_to_target())
                                                            : nlohmann::json(nullptr)},
                          {"final_success", run.last_success()},
                          {"final_score", run.has_last_score() ? nlohmann::json(run.last_score())
                                                               : nlohmann::json(nullptr)},
                          {"target_success", run.target_success()},
                          {"wall_s", r.wall_s},
                          {"checkpoint_id", run.latest_checkpoint_id()}});
  }
  // A part that did not reach its target adds all the steps it spent: the total says so.
  table.add({"total", "", "", "",
             std::to_string(total_steps) +
                 (not_reached ? " (" + std::to_string(not_reached) + " not reached)" : ""),
             "", "", "", fixed(total_wall, 1) + " s", ""});
  std::printf("\n");
  table.print(stdout);
  std::printf(
      "\nheld-out through the services: success %.3f over %d episodes (seed %llu, %s/%s/%s, %s "
      "hand)",
      held_out.success_rate(), held_out.episodes, static_cast<unsigned long long>(args.eval_seed),
      args.experts.world.c_str(), args.experts.robot.c_str(), args.experts.object.c_str(),
      actuation.c_str());
  if (!held_out.sequences.empty())
    std::printf(", choices %s x%d", held_out.sequences.front().first.c_str(),
                held_out.sequences.front().second);
  std::printf("\n");
  const train::v1::TrainingRun& last = results.back().run;
  const nlohmann::json out = {{"world", args.experts.world},
                              {"actuation", actuation},
                              {"robot", args.experts.robot},
                              {"object", args.experts.object},
                              {"seed", args.experts.seed},
                              {"gemm_path", last.gemm_path()},
                              {"code_commit", last.code_commit()},
                              {"roles", json_roles},
                              {"total_steps_to_target", total_steps},
                              {"total_wall_s", total_wall},
                              {"held_out",
                               {{"episodes", held_out.episodes},
                                {"success_rate", held_out.success_rate()},
                                {"seed", args.eval_seed},
                                {"sequences", held_out.sequences}}}};
  if (!args.expected.empty()) std::printf("%s", compare_with_expected(out, args.expected).c_str());
  if (!args.json_out.empty()) {
    std::ofstream file(args.json_out);
    file << out.dump(2) << "\n";
    if (!file.flush()) throw Error(ErrorCode::kUnavailable, "could not write " + args.json_out);
  }
  return 0;
}

}  // namespace pnp::pnpctl
