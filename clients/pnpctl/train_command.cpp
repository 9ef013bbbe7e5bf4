#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/rpc.h"
#include "clients/pnpctl/run_display.h"
#include "clients/pnpctl/run_watch.h"
#include "clients/pnpctl/table.h"
#include "common/secret_token.h"
#include "pnp/train/v1/train_service.grpc.pb.h"

namespace pnp::pnpctl {

train::v1::CreateTrainingRunRequest make_request(const TrainArgs& a) {
  train::v1::CreateTrainingRunRequest r;
  // One key per run meant: a call retried after its answer was lost returns that run.
  r.set_request_id(secret_token_hex(16));
  r.set_role(parse_role(a.role, "--role"));
  r.set_algorithm(parse_algorithm(
      !a.algorithm.empty() ? a.algorithm : (a.role == "hlc" ? "a3c" : "ddpg_her"), "--algo"));
  r.set_robot(parse_robot(a.robot, "--robot"));
  r.set_object(parse_object(a.object, "--object"));
  r.set_world(parse_world(a.world, "--world"));
  r.set_actuation(parse_actuation(a.actuation, a.robot, "--actuation"));
  r.set_seed(a.seed);
  r.set_preset(a.preset);
  if (a.max_steps) r.mutable_stop()->set_max_steps(a.max_steps);
  if (a.target_success) r.mutable_stop()->set_target_success(a.target_success);
  if (a.eval_interval) r.mutable_stop()->set_eval_interval_steps(a.eval_interval);
  if (a.eval_episodes) r.mutable_stop()->set_eval_episodes(a.eval_episodes);
  if (a.updates_per_transition)
    r.mutable_ddpg()->set_updates_per_transition(a.updates_per_transition);
  for (int width : a.hidden) r.mutable_ddpg()->add_hidden(width);
  if (a.workers) r.mutable_a3c()->set_workers(a.workers);
  r.set_parent_checkpoint_id(a.parent);
  for (auto id : a.prefix) r.add_prefix_checkpoint_ids(id);
  for (auto id : a.experts) r.add_expert_checkpoint_ids(id);
  for (auto id : a.successors) r.add_successor_checkpoint_ids(id);
  return r;
}

namespace {

// What Ctrl-C during the watch prints: the run is the server's, and goes on. A signal
// handler cannot be handed state, so the line lives here (written once, before the watch).
std::array<char, 160> interrupt_message{};
std::size_t interrupt_message_size = 0;

void on_interrupt(int) {
  [[maybe_unused]] const auto written =
      ::write(STDERR_FILENO, interrupt_message.data(), interrupt_message_size);
  ::_exit(130);
}

void explain_interrupt(std::int64_t run_id) {
  const int n = std::snprintf(interrupt_message.data(), interrupt_message.size(),
                              "\npnpctl: stopped watching; run %lld goes on on the server "
                              "(pnpctl cancel %lld stops it)\n",
                              static_cast<long long>(run_id), static_cast<long long>(run_id));
  interrupt_message_size = static_cast<std::size_t>(std::max(n, 0));
  std::signal(SIGINT, on_interrupt);
}

}  // namespace

int cancel_command(const Endpoints& endpoints, std::int64_t run_id, const std::string& via) {
  // Any training service reads the shared store; the run's own role's service owns it.
  train::v1::GetTrainingRunRequest get;
  get.set_run_id(run_id);
  train::v1::GetTrainingRunResponse found;
  const std::string& reader = endpoints.training(via);
  check(train::v1::TrainingService::NewStub(endpoints.channel(reader))
            ->GetTrainingRun(context_with_deadline().get(), get, &found),
        "GetTrainingRun", reader);
  const std::string& owner = endpoints.training(short_name(found.run().role()));
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(owner));
  train::v1::CancelTrainingRunRequest request;
  request.set_run_id(run_id);
  train::v1::CancelTrainingRunResponse cancelled;
  check(stub->CancelTrainingRun(context_with_deadline().get(), request, &cancelled),
        "CancelTrainingRun", owner);
  // A running run stops at its next round of rollouts and updates: wait for that.
  train::v1::TrainingRun run = cancelled.run();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (run.state() == train::v1::RUN_STATE_RUNNING &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    check(stub->GetTrainingRun(context_with_deadline().get(), get, &found), "GetTrainingRun",
          owner);
    run = found.run();
  }
  std::printf("run %lld (%s) %s at %lld steps\n", static_cast<long long>(run_id),
              short_name(run.role()).c_str(), short_name(run.state()).c_str(),
              static_cast<long long>(run.env_steps()));
  return run.state() == train::v1::RUN_STATE_CANCELLED ? 0 : 1;
}

int train_command(const Endpoints& endpoints, const TrainArgs& args) {
  const std::string& address = endpoints.training(args.role);
  const auto request = make_request(args);
  auto stub = train::v1::TrainingService::NewStub(endpoints.channel(address));
  train::v1::CreateTrainingRunResponse created;
  check(stub->CreateTrainingRun(context_with_deadline().get(), request, &created),
        "CreateTrainingRun", address);
  std::printf("run %lld created (%s)\n", static_cast<long long>(created.run().run_id()),
              short_name(created.run().state()).c_str());
  std::fflush(stdout);  // before the progress lines on stderr, even when redirected
  if (args.detach) return 0;
  explain_interrupt(created.run().run_id());
  const auto run = watch_run(endpoints, address, created.run().run_id(), {args.quiet, stderr});
  const std::string target = run.reached()
                                 ? "target " + fixed(run.target_success(), 2) + " reached at " +
                                       std::to_string(run.steps_to_target()) + " steps"
                                 : "target " + fixed(run.target_success(), 2) + " not reached";
  std::printf("run %lld %s: %lld steps, score %s, success %.2f, %s, latest checkpoint %lld\n",
              static_cast<long long>(run.run_id()), outcome_text(run).c_str(),
              static_cast<long long>(run.env_steps()), score_text(run).c_str(), run.last_success(),
              target.c_str(), static_cast<long long>(run.latest_checkpoint_id()));
  if (run.state() == train::v1::RUN_STATE_FAILED)
    std::fprintf(stderr, "pnpctl: run %lld failed: %s\n", static_cast<long long>(run.run_id()),
                 run.error().c_str());
  return run.state() == train::v1::RUN_STATE_SUCCEEDED ? 0 : 1;
}

}  // namespace pnp::pnpctl
