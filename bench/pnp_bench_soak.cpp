// pnp-bench-soak: the platform under a long mixed load, as real server processes on
// loopback: the simulation, inference and (approach) training servers over one store with
// the checked-in Panda hierarchy promoted. For --minutes (default 10):
//   - --predict-clients (16) threads call Predict in a loop;
//   - --sessions (8) threads play whole episodes through PredictSession, stepping a local
//     simulation with the answers;
//   - --sim-clients (2) threads step environment batches on the simulation server;
//   - the training server trains approach experts back to back, its rollouts on the
//     simulation server (--sim-address), each run to a step cap;
//   - one thread calls Ping (the empty RPC: the floor the Predict latency is compared to).
// Every error is counted (a soak passes with none). The resident memory (VmRSS) of each
// server is sampled every 10 s; a server whose RSS grows more than 10% from minute 2 to the
// end fails the leak check. Prints one JSON object; exits 1 if any check fails.
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "common/percentile.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "services/common/convert.h"
#include "sim/pick_place_env.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"
#include "tools/common/cli.h"

namespace {

using namespace pnp;
using Clock = std::chrono::steady_clock;
namespace pv1 = policy::v1;
namespace sv1 = sim::v1;
namespace tv1 = train::v1;

constexpr auto kCallDeadline = std::chrono::seconds(10);
constexpr auto kRssPeriod = std::chrono::seconds(10);
constexpr double kRssGrowthLimit = 0.10;

// What one kind of load saw: latencies of its calls and its errors (with a few messages).
class Tally {
 public:
  void ok(double us) {
    std::lock_guard lock(mutex_);
    us_.push_back(us);
  }
  void error(const grpc::Status& status) {
    std::lock_guard lock(mutex_);
    ++errors_;
    if (messages_.size() < 5) messages_.push_back(status.error_message());
  }
  long errors() const {
    std::lock_guard lock(mutex_);
    return errors_;
  }
  double p(double q) const {
    std::lock_guard lock(mutex_);
    return us_.empty() ? 0 : percentile(us_, q);
  }
  nlohmann::json to_json() const {
    std::lock_guard lock(mutex_);
    return {{"calls", us_.size()},
            {"errors", errors_},
            {"p50_us", us_.empty() ? 0 : percentile(us_, 0.5)},
            {"p99_us", us_.empty() ? 0 : percentile(us_, 0.99)},
            {"error_messages", messages_}};
  }

 private:
  mutable std::mutex mutex_;
  std::vector<double> us_;
  long errors_ = 0;
  std::vector<std::string> messages_;
};

std::unique_ptr<grpc::ClientContext> call_context() {
  auto c = std::make_unique<grpc::ClientContext>();
  c->set_deadline(std::chrono::system_clock::now() + kCallDeadline);
  return c;
}

double micros_since(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

// A Predict request from a Panda world after `seed`'s reset.
pv1::PredictRequest predict_request(std::uint64_t seed) {
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kPanda, sim::ObjectShape::kBlock));
  env.reset(seed);
  pv1::PredictRequest r;
  services::to_proto(env.observation(), *r.mutable_observation());
  services::to_proto(env.episode_goal(), *r.mutable_goal());
  return r;
}

void predict_loop(pv1::PolicyService::Stub& stub, std::uint64_t seed, Tally& tally,
                  const std::atomic<bool>& stop) {
  const auto request = predict_request(seed);
  pv1::PredictResponse response;
  while (!stop) {
    const auto start = Clock::now();
    const auto status = stub.Predict(call_context().get(), request, &response);
    status.ok() ? tally.ok(micros_since(start)) : tally.error(status);
  }
}

void ping_loop(pv1::PolicyService::Stub& stub, Tally& tally, const std::atomic<bool>& stop) {
  pv1::PingResponse response;
  while (!stop) {
    const auto start = Clock::now();
    const auto status = stub.Ping(call_context().get(), {}, &response);
    status.ok() ? tally.ok(micros_since(start)) : tally.error(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Whole episodes through PredictSession; each answer's action steps a local world.
void session_loop(pv1::PolicyService::Stub& stub, std::uint64_t seed, Tally& tally,
                  const std::atomic<bool>& stop) {
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kPanda, sim::ObjectShape::kBlock));
  pv1::PredictSessionRequest request;
  pv1::PredictSessionResponse response;
  for (std::uint64_t episode = 0; !stop; ++episode) {
    env.reset(seed * 100'000 + episode);
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::minutes(2));
    auto stream = stub.PredictSession(&context);
    while (!env.needs_reset() && !stop) {
      services::to_proto(env.observation(), *request.mutable_observation());
      services::to_proto(env.episode_goal(), *request.mutable_goal());
      const auto start = Clock::now();
      if (!stream->Write(request) || !stream->Read(&response)) break;
      tally.ok(micros_since(start));
      const auto& a = response.prediction().action();
      const std::array<double, 4> action{a.dx(), a.dy(), a.dz(), a.gripper()};
      const sim::Goal goal = env.episode_goal();
      env.step(std::span<const double>(action), std::span<const double>(goal.data(), 3),
               sim::Objective::kTask);
    }
    stream->WritesDone();
    while (stream->Read(&response)) {
    }
    const auto status = stream->Finish();
    if (!status.ok()) tally.error(status);
  }
}

// Steps a batch of 4 environments on the simulation server with random-ish actions.
void sim_loop(sv1::SimulationService::Stub& stub, std::uint64_t seed, Tally& tally,
              const std::atomic<bool>& stop) {
  sv1::CreateEnvRequest create;
  create.set_robot(common::v1::ROBOT_PANDA);
  create.set_object(common::v1::OBJECT_SHAPE_BLOCK);
  create.set_count(4);
  create.set_seed(seed);
  sv1::CreateEnvResponse created;
  if (const auto s = stub.CreateEnv(call_context().get(), create, &created); !s.ok())
    return tally.error(s);
  sv1::ResetRequest reset;
  reset.set_env_id(created.env_id());
  sv1::StepRequest step;
  step.set_env_id(created.env_id());
  for (int i = 0; i < 4; ++i) {
    auto& a = *step.add_actions();
    a.set_index(i);
    a.set_objective(sv1::OBJECTIVE_TASK);
    a.mutable_action()->set_dx(0.3 * (i - 1.5));
    a.mutable_action()->set_dz(-0.2);
  }
  sv1::ResetResponse reset_out;
  sv1::StepResponse step_out;
  for (int n = 0; !stop; ++n) {
    const auto start = Clock::now();
    const auto status = n % 50 == 0 ? stub.Reset(call_context().get(), reset, &reset_out)
                                    : stub.Step(call_context().get(), step, &step_out);
    status.ok() ? tally.ok(micros_since(start)) : tally.error(status);
  }
}

// Approach runs back to back, each to `steps`; counts finished runs, failed ones as errors.
// Polls each run's state (once a second) so that the end of the soak cancels the run in
// flight instead of waiting for it.
void training_loop(tv1::TrainingService::Stub& stub, long long steps, Tally& tally,
                   std::atomic<int>& finished, const std::atomic<bool>& stop) {
  for (std::uint64_t seed = 1; !stop; ++seed) {
    tv1::CreateTrainingRunRequest request;
    request.set_role(common::v1::ROLE_APPROACH);
    request.set_algorithm(tv1::ALGORITHM_DDPG_HER);
    request.set_robot(common::v1::ROBOT_PANDA);
    request.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    request.set_seed(seed);
    request.mutable_stop()->set_max_steps(steps);
    request.mutable_stop()->set_target_success(1.0);
    tv1::CreateTrainingRunResponse created;
    const auto start = Clock::now();
    if (const auto s = stub.CreateTrainingRun(call_context().get(), request, &created); !s.ok())
      return tally.error(s);
    tv1::GetTrainingRunRequest get;
    get.set_run_id(created.run().run_id());
    tv1::GetTrainingRunResponse run;
    for (;;) {
      if (const auto s = stub.GetTrainingRun(call_context().get(), get, &run); !s.ok())
        return tally.error(s);
      const auto state = run.run().state();
      if (state == tv1::RUN_STATE_SUCCEEDED) {
        tally.ok(micros_since(start));
        ++finished;
        break;
      }
      if (state == tv1::RUN_STATE_FAILED || state == tv1::RUN_STATE_CANCELLED) {
        return tally.error(grpc::Status(grpc::StatusCode::ABORTED,
                                        "run " + std::to_string(get.run_id()) + " ended " +
                                            tv1::RunState_Name(state) + ": " + run.run().error()));
      }
      if (stop) {
        tv1::CancelTrainingRunRequest cancel;
        cancel.set_run_id(get.run_id());
        tv1::CancelTrainingRunResponse cancelled;
        stub.CancelTrainingRun(call_context().get(), cancel, &cancelled);
        return;
      }
      std::this_thread::sleep_for(std::chrono::seconds(1));
    }
  }
}

long rss_kib(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

struct Options {
  double minutes = 10;
  int predict_clients = 16, sessions = 8, sim_clients = 2;
  long long run_steps = 5000;
  std::string bin_dir = PNP_BIN_DIR;
};

nlohmann::json soak(const Options& o) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("pnp_soak_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string db = (dir / "pnp.db").string();
  {
    store::RunStore store(db);
    store::import_hierarchy(store, std::filesystem::path(PNP_SOURCE_DIR) / "tests/data/panda_block",
                            "panda", "block");
  }
  using integration::ChildProcess;
  const auto bin = [&](const std::string& name) { return o.bin_dir + "/" + name; };
  ChildProcess sim("sim", {bin("pnp-sim-server"), "--address", "127.0.0.1:0"}, dir);
  const std::string sim_address = "127.0.0.1:" + std::to_string(sim.port());
  ChildProcess inference(
      "inference", {bin("pnp-inference-server"), "--address", "127.0.0.1:0", "--db", db}, dir);
  ChildProcess train("train",
                     {bin("pnp-train-server"), "--address", "127.0.0.1:0", "--role", "approach",
                      "--threads", "1", "--db", db, "--sim-address", sim_address},
                     dir);
  const auto channel = [](int port) {
    if (port <= 0) throw Error(ErrorCode::kUnavailable, "a server did not start (see its log)");
    return grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                               grpc::InsecureChannelCredentials());
  };
  const auto policy_stub = pv1::PolicyService::NewStub(channel(inference.port()));
  const auto sim_stub = sv1::SimulationService::NewStub(channel(sim.port()));
  const auto train_stub = tv1::TrainingService::NewStub(channel(train.port()));

  std::map<std::string, Tally> tallies;
  std::atomic<bool> stop{false};
  std::atomic<int> runs_finished{0};
  std::vector<std::jthread> load;
  // Each loop gets its tally by reference, taken before any thread starts.
  Tally& predict = tallies["predict"];
  Tally& session = tallies["session_step"];
  Tally& stepping = tallies["sim"];
  Tally& training = tallies["training_run"];
  Tally& ping = tallies["ping"];
  for (std::uint64_t i = 0; i < static_cast<std::uint64_t>(o.predict_clients); ++i)
    load.emplace_back([&, i] { predict_loop(*policy_stub, 1000 + i, predict, stop); });
  for (std::uint64_t i = 0; i < static_cast<std::uint64_t>(o.sessions); ++i)
    load.emplace_back([&, i] { session_loop(*policy_stub, 1 + i, session, stop); });
  for (std::uint64_t i = 0; i < static_cast<std::uint64_t>(o.sim_clients); ++i)
    load.emplace_back([&, i] { sim_loop(*sim_stub, 7 + i, stepping, stop); });
  load.emplace_back(
      [&] { training_loop(*train_stub, o.run_steps, training, runs_finished, stop); });
  load.emplace_back([&] { ping_loop(*policy_stub, ping, stop); });

  // Samples every 10 s: [seconds, rss per server].
  std::vector<std::pair<double, std::map<std::string, long>>> samples;
  const std::vector<ChildProcess*> servers{&sim, &inference, &train};
  const auto begin = Clock::now();
  const auto end = begin + std::chrono::duration<double, std::ratio<60>>(o.minutes);
  while (Clock::now() < end) {
    const auto left = std::chrono::duration_cast<Clock::duration>(end - Clock::now());
    std::this_thread::sleep_for(std::min<Clock::duration>(kRssPeriod, left));
    std::map<std::string, long> rss;
    for (auto* s : servers) rss[s->name()] = s->running() ? rss_kib(s->pid()) : 0;
    samples.emplace_back(std::chrono::duration<double>(Clock::now() - begin).count(), rss);
  }
  stop = true;
  load.clear();  // joins

  nlohmann::json out{{"benchmark", "soak"},
                     {"minutes", o.minutes},
                     {"predict_clients", o.predict_clients},
                     {"sessions", o.sessions},
                     {"sim_clients", o.sim_clients},
                     {"training_runs_finished", runs_finished.load()},
                     {"run_steps", o.run_steps}};
  long errors = 0;
  for (const auto& [kind, tally] : tallies) {
    out["calls"][kind] = tally.to_json();
    errors += tally.errors();
  }
  out["errors"] = errors;
  out["predict_p99_over_ping_p99"] = ping.p(0.99) > 0 ? predict.p(0.99) / ping.p(0.99) : 0;
  // RSS from the first sample at or after minute 2 (or a fifth of the run) to the last.
  const double warm_s = std::min(120.0, o.minutes * 12.0);
  bool leak_ok = !samples.empty();
  for (auto* s : servers) {
    long from = 0, to = samples.empty() ? 0 : samples.back().second.at(s->name());
    for (const auto& [t, rss] : samples)
      if (t >= warm_s) {
        from = rss.at(s->name());
        break;
      }
    const double growth = from > 0 ? static_cast<double>(to - from) / static_cast<double>(from) : 1;
    const bool alive = s->running();
    out["rss"][s->name()] = {
        {"from_kib", from}, {"to_kib", to}, {"growth", growth}, {"running", alive}};
    leak_ok = leak_ok && alive && growth <= kRssGrowthLimit;
  }
  out["rss_window_s"] = {warm_s, samples.empty() ? 0 : samples.back().first};
  // The whole series, so a reader tells a leak (steady growth) from a plateau.
  for (const auto& [t, rss] : samples) {
    nlohmann::json sample{{"t_s", std::round(t)}};
    for (const auto& [name, kib] : rss) sample[name + "_kib"] = kib;
    out["rss_samples"].push_back(sample);
  }
  out["ok"] = errors == 0 && leak_ok;
  for (auto* s : servers) s->terminate_and_wait(std::chrono::seconds(20));
  std::filesystem::remove_all(dir);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The platform under a long mixed load: errors, latency, RSS", "pnp-bench-soak"};
  Options o;
  app.add_option("--minutes", o.minutes, "how long the load runs")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--predict-clients", o.predict_clients, "Predict loops")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--sessions", o.sessions, "PredictSession episode loops")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--sim-clients", o.sim_clients, "simulation stepping loops")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--run-steps", o.run_steps, "environment steps per training run")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--bin-dir", o.bin_dir, "where the server binaries are")->capture_default_str();
  bool failed = false;  // the soak ran and broke one of its rules (not --help or --version)
  const int rc = tools::run_tool(app, argc, argv, [&] {
    const auto result = soak(o);
    std::cout << result.dump(2) << std::endl;
    failed = !result["ok"].get<bool>();
  });
  return rc != 0 ? rc : (failed ? 1 : 0);
}
