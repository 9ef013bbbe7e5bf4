// Integration: the platform as scripts/run starts it (the simulation service, the four
// training services and the inference service as real processes on free loopback ports,
// over one SQLite file), driven by the real pnpctl; then what is on disk, read with the
// SQLite C API. Budgets are tiny: the runs need not learn, only go through.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/integration/child_process.h"
#include "tests/integration/metrics_scrape.h"
#include "tests/integration/store_reader.h"

namespace pnp::integration {
namespace {

const std::vector<std::string> kRoles{"approach", "manipulate", "retract", "hlc"};

std::string bin(const std::string& program) {
  return std::string(PNP_BIN_DIR) + "/" + program;
}

// "a b c" as {"a", "b", "c"}: command lines that read as typed.
std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

// pnp-train-server for `role` over `db`, on a free loopback port, one trainer thread.
std::vector<std::string> train_server(const std::string& role, const std::string& db) {
  auto args = words("--address 127.0.0.1:0 --threads 1 --role " + role);
  args.insert(args.begin(), bin("pnp-train-server"));
  args.push_back("--db");
  args.push_back(db);
  return args;
}

// A pnpctl invocation run to its end.
struct CliResult {
  std::optional<ExitStatus> status;  // empty: still running after the guard, killed
  std::string out, err;
};

CliResult run_pnpctl(const TempDir& dir, const std::string& name, std::vector<std::string> args,
                     std::chrono::milliseconds guard = 300s) {
  args.insert(args.begin(), bin("pnpctl"));
  ChildProcess cli(name, std::move(args), dir.path());
  CliResult result;
  result.status = cli.wait(guard);
  if (!result.status) cli.kill();
  result.out = cli.stdout_text();
  result.err = cli.stderr_text();
  return result;
}

void expect_clean_exit(ChildProcess& server) {
  const auto status = server.terminate_and_wait();
  ASSERT_TRUE(status) << "did not stop within the guard: " << server.diagnostics();
  EXPECT_TRUE(status->ok()) << server.diagnostics();
}

// The platform: sim, four trainers (retract's rollouts on the simulation service, the
// others in process) and inference, over one store.
TEST(Pipeline, RunsEndToEndThroughTheServicesAndLeavesAConsistentStore) {
  TempDir dir("pipeline");
  const std::string db = dir.file("pnp.db");
  ChildProcess sim(
      "sim",
      {bin("pnp-sim-server"), "--address", "127.0.0.1:0", "--metrics-address", "127.0.0.1:0"},
      dir.path());
  const int sim_port = sim.port();
  ASSERT_GT(sim_port, 0) << sim.diagnostics();
  std::map<std::string, std::unique_ptr<ChildProcess>> trainers;
  std::map<std::string, int> ports;
  for (const auto& role : kRoles) {
    std::vector<std::string> args = train_server(role, db);
    if (role == "retract") {
      args.push_back("--sim-address");
      args.push_back(loopback(sim_port));
    }
    trainers[role] = std::make_unique<ChildProcess>("train-" + role, args, dir.path());
  }
  ChildProcess inference(  // the store from $PNP_DB, without --db; it may start first
      "inference",
      {bin("pnp-inference-server"), "--address", "127.0.0.1:0", "--reload-ms", "100",
       "--create-db"},
      dir.path(), {{"PNP_DB", db}});
  for (const auto& role : kRoles) {
    ports[role] = trainers[role]->port();
    ASSERT_GT(ports[role], 0) << trainers[role]->diagnostics();
  }
  const int inference_port = inference.port();
  ASSERT_GT(inference_port, 0) << inference.diagnostics();

  const std::vector<std::string> endpoints{"--sim",        loopback(sim_port),
                                           "--approach",   loopback(ports["approach"]),
                                           "--manipulate", loopback(ports["manipulate"]),
                                           "--retract",    loopback(ports["retract"]),
                                           "--hlc",        loopback(ports["hlc"]),
                                           "--e2e",        "127.0.0.1:1",
                                           "--inference",  loopback(inference_port)};
  auto command = [&](std::vector<std::string> args) {
    args.insert(args.begin(), endpoints.begin(), endpoints.end());
    return args;
  };

  const CliResult health = run_pnpctl(
      dir, "pnpctl-health",
      command({"health", "--only", "sim,approach,manipulate,retract,hlc,inference"}), 60s);
  ASSERT_TRUE(health.status && health.status->ok()) << health.out << health.err;

  const std::string results_file = dir.file("results.json");
  const int held_out_episodes = 3;
  auto pipeline_args = command(words(
      "pipeline --seed 1 --max-steps 400 --eval-interval 200 --eval-episodes 4 --hidden 16,16 "
      "--hlc-max-steps 300 --hlc-workers 1 --quiet --wait 60 --held-out-episodes " +
      std::to_string(held_out_episodes)));
  pipeline_args.push_back("--json-out");
  pipeline_args.push_back(results_file);
  const CliResult pipeline = run_pnpctl(dir, "pnpctl-pipeline", pipeline_args);
  ASSERT_TRUE(pipeline.status) << "pnpctl pipeline did not finish\n" << pipeline.err;
  ASSERT_TRUE(pipeline.status->ok()) << pipeline.status->describe() << "\n"
                                     << pipeline.out << pipeline.err;
  EXPECT_NE(pipeline.out.find("held-out through the services"), std::string::npos) << pipeline.out;

  // The hierarchy was trained on the Fetch arm in the default (gym) world: evaluating it on
  // the Panda warns, and
  // --strict refuses.
  const CliResult other_robot = run_pnpctl(
      dir, "pnpctl-evaluate-panda", command(words("evaluate --episodes 2 --robot panda")), 120s);
  ASSERT_TRUE(other_robot.status && other_robot.status->ok()) << other_robot.err;
  EXPECT_NE(other_robot.err.find("pnpctl: warning: evaluating on gym/panda/block (mocap hand), but "
                                 "the served policy was trained elsewhere: approach "
                                 "(gym/fetch/block, mocap hand)"),
            std::string::npos)
      << other_robot.err;
  const CliResult strict =
      run_pnpctl(dir, "pnpctl-evaluate-strict",
                 command(words("evaluate --episodes 2 --robot panda --strict")), 120s);
  ASSERT_TRUE(strict.status);
  EXPECT_EQ(strict.status->describe(), "exit 1") << strict.err;
  EXPECT_NE(strict.err.find("pnpctl: error: evaluating on gym/panda/block"), std::string::npos)
      << strict.err;
  // So does another world profile of the same robot.
  const CliResult other_world =
      run_pnpctl(dir, "pnpctl-evaluate-paper",
                 command(words("evaluate --episodes 2 --world paper --strict")), 120s);
  ASSERT_TRUE(other_world.status);
  EXPECT_EQ(other_world.status->describe(), "exit 1") << other_world.err;
  EXPECT_NE(other_world.err.find("evaluating on paper/fetch/block (mocap hand), but the served "
                                 "policy was trained elsewhere: approach (gym/fetch/block, mocap "
                                 "hand)"),
            std::string::npos)
      << other_world.err;

  // The results as JSON.
  const auto results = nlohmann::json::parse(read_file(results_file), nullptr, false);
  ASSERT_FALSE(results.is_discarded()) << read_file(results_file);
  ASSERT_EQ(results.at("roles").size(), kRoles.size()) << results.dump(2);
  std::map<std::string, long long> run_of, checkpoint_of, steps_of;
  for (std::size_t i = 0; i < kRoles.size(); ++i) {
    const auto& r = results.at("roles").at(i);
    EXPECT_EQ(r.at("role").get<std::string>(), kRoles[i]);
    EXPECT_GT(r.at("run_id").get<long long>(), 0);
    EXPECT_GT(r.at("checkpoint_id").get<long long>(), 0);
    EXPECT_GT(r.at("env_steps").get<long long>(), 0);
    EXPECT_GE(r.at("final_success").get<double>(), 0.0);
    EXPECT_LE(r.at("final_success").get<double>(), 1.0);
    EXPECT_EQ(r.at("steps_to_target").is_null(), !r.at("reached").get<bool>());
    run_of[kRoles[i]] = r.at("run_id").get<long long>();
    checkpoint_of[kRoles[i]] = r.at("checkpoint_id").get<long long>();
    steps_of[kRoles[i]] = r.at("env_steps").get<long long>();
  }
  const auto& held_out = results.at("held_out");
  EXPECT_EQ(held_out.at("episodes").get<int>(), held_out_episodes);
  EXPECT_GE(held_out.at("success_rate").get<double>(), 0.0);
  EXPECT_LE(held_out.at("success_rate").get<double>(), 1.0);
  EXPECT_EQ(held_out.at("seed").get<long long>(), 424242);
  int sequences = 0;
  for (const auto& s : held_out.at("sequences")) sequences += s.at(1).get<int>();
  EXPECT_EQ(sequences, held_out_episodes);

  // The retract trainer ran its rollouts on the simulation service (the held-out
  // evaluation steps it with unary calls, never with a rollout stream).
  const int sim_metrics_port = metrics_port(sim);
  ASSERT_GT(sim_metrics_port, 0) << sim.diagnostics();
  const std::string exposition = http_get(sim_metrics_port, "/metrics");
  const std::string sim_service = "grpc_service=\"pnp.sim.v1.SimulationService\"";
  EXPECT_GT(metric_sum(exposition, "grpc_server_handled_total",
                       {sim_service, "grpc_method=\"StreamRollout\"", "grpc_code=\"OK\""}),
            0.0)
      << exposition;
  EXPECT_GT(metric_sum(exposition, "grpc_server_handled_total",
                       {sim_service, "grpc_method=\"Step\"", "grpc_code=\"OK\""}),
            0.0)
      << exposition;

  // Every server drains and exits 0.
  expect_clean_exit(inference);
  for (const auto& role : kRoles) expect_clean_exit(*trainers[role]);
  expect_clean_exit(sim);

  // The store, as any reader finds it.
  const StoreReader store(db);
  EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
  EXPECT_TRUE(store.rows("PRAGMA foreign_key_check").empty());
  EXPECT_EQ(store.integer("SELECT COUNT(*) FROM runs"), 4);
  for (const auto& role : kRoles) {
    SCOPED_TRACE(role);
    const long long run = run_of[role];
    const auto rows = store.rows(
        "SELECT role, state, error, env_steps, finished_ms IS NOT NULL FROM runs WHERE id = ?",
        {run});
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0], (SqlRow{role, "succeeded", "", std::to_string(steps_of[role]), "1"}));
    EXPECT_GT(store.integer("SELECT COUNT(*) FROM metrics WHERE run_id = ?", {run}), 0);
    EXPECT_GT(store.integer("SELECT COUNT(*) FROM checkpoints WHERE run_id = ?", {run}), 0);
    EXPECT_EQ(store.integer("SELECT COUNT(*) FROM checkpoints WHERE run_id = ? AND "
                            "(length(blob) = 0 OR length(blob) != size_bytes OR role != '" +
                                role + "')",
                            {run}),
              0);
    // The checkpoint the pipeline promoted: this run's, of this role, and served.
    EXPECT_EQ(store.rows("SELECT run_id, role, length(blob) > 0 FROM checkpoints WHERE id = ?",
                         {checkpoint_of[role]}),
              (std::vector<SqlRow>{{std::to_string(run), role, "1"}}));
    EXPECT_EQ(store.rows("SELECT checkpoint_id FROM promotions WHERE role = '" + role + "'"),
              (std::vector<SqlRow>{{std::to_string(checkpoint_of[role])}}));
  }
  // Chained: each expert trained after the learned ones before it; the choreographer
  // over the three promoted experts.
  auto experts_of = [&](const std::string& role) {
    const auto config = nlohmann::json::parse(
        store.text("SELECT config_json FROM runs WHERE id = ?", {run_of[role]}));
    return config.at("checkpoints").at("experts").get<std::vector<long long>>();
  };
  EXPECT_EQ(experts_of("approach"), std::vector<long long>{});
  EXPECT_EQ(experts_of("manipulate"), std::vector<long long>{checkpoint_of["approach"]});
  EXPECT_EQ(experts_of("retract"),
            (std::vector<long long>{checkpoint_of["approach"], checkpoint_of["manipulate"]}));
  EXPECT_EQ(experts_of("hlc"),
            (std::vector<long long>{checkpoint_of["approach"], checkpoint_of["manipulate"],
                                    checkpoint_of["retract"]}));
}

// The same run on a trainer with its rollouts on the simulation service and on one with
// them in process: the same learning curve and the same weights, bit for bit.
TEST(Pipeline, ATrainerOnTheSimulationServiceTrainsAsInProcess) {
  TempDir dir("remote_rollouts");
  ChildProcess sim("sim", {bin("pnp-sim-server"), "--address", "127.0.0.1:0"}, dir.path());
  const int sim_port = sim.port();
  ASSERT_GT(sim_port, 0) << sim.diagnostics();
  ChildProcess local("train-local", train_server("approach", dir.file("local.db")), dir.path());
  auto remote_args = train_server("approach", dir.file("remote.db"));
  remote_args.push_back("--sim-address");
  remote_args.push_back(loopback(sim_port));
  ChildProcess remote("train-remote", remote_args, dir.path());
  const int local_port = local.port();
  const int remote_port = remote.port();
  ASSERT_GT(local_port, 0) << local.diagnostics();
  ASSERT_GT(remote_port, 0) << remote.diagnostics();
  const auto train = words(
      "train --role approach --seed 2 --max-steps 400 --eval-interval 200 --eval-episodes 4 "
      "--hidden 16,16 --quiet");
  for (const auto& [name, port] : {std::pair{"local", local_port}, {"remote", remote_port}}) {
    std::vector<std::string> args{"--approach", loopback(port)};
    args.insert(args.end(), train.begin(), train.end());
    const CliResult result = run_pnpctl(dir, std::string("pnpctl-") + name, args);
    ASSERT_TRUE(result.status && result.status->ok()) << name << "\n" << result.out << result.err;
  }
  expect_clean_exit(local);
  expect_clean_exit(remote);
  expect_clean_exit(sim);

  const StoreReader local_store(dir.file("local.db"));
  const StoreReader remote_store(dir.file("remote.db"));
  const std::string checkpoints =
      "SELECT env_steps, eval_success, checksum, size_bytes "
      "FROM checkpoints ORDER BY id";
  const std::string curve =
      "SELECT env_steps, episodes, task_success, subtask_success, "
      "critic_loss, actor_loss, updates FROM metrics ORDER BY env_steps";
  const auto local_checkpoints = local_store.rows(checkpoints);
  ASSERT_FALSE(local_checkpoints.empty());
  EXPECT_EQ(remote_store.rows(checkpoints), local_checkpoints);
  EXPECT_EQ(remote_store.rows(curve), local_store.rows(curve));
  EXPECT_EQ(remote_store.text("SELECT state FROM runs"), "succeeded");
}

// Refusals that only the training service can make reach pnpctl's user as one line with
// the field, and leave nothing in the store.
// On the arm-actuated world the experts chain backward: retract first, then each one
// judged with the learned experts after it; the served hierarchy says it was trained
// through the arm. Every trainer and the held-out evaluation step the arm world.
TEST(Pipeline, OnTheArmWorldTheExpertsChainBackward) {
  TempDir dir("pipeline_arm");
  const std::string db = dir.file("pnp.db");
  ChildProcess sim("sim", {bin("pnp-sim-server"), "--address", "127.0.0.1:0"}, dir.path());
  std::map<std::string, std::unique_ptr<ChildProcess>> trainers;
  for (const auto& role : kRoles)
    trainers[role] =
        std::make_unique<ChildProcess>("train-" + role, train_server(role, db), dir.path());
  ChildProcess inference("inference",
                         {bin("pnp-inference-server"), "--address", "127.0.0.1:0", "--reload-ms",
                          "100", "--create-db", "--db", db},
                         dir.path());
  std::vector<std::string> args{"--sim",       loopback(sim.port()),
                                "--inference", loopback(inference.port()),
                                "--e2e",       "127.0.0.1:1"};
  for (const auto& role : kRoles) {
    ASSERT_GT(trainers[role]->port(), 0) << trainers[role]->diagnostics();
    args.push_back("--" + role);
    args.push_back(loopback(trainers[role]->port()));
  }
  const std::string results_file = dir.file("results.json");
  for (const std::string& word :
       words("pipeline --robot panda --actuation arm --seed 1 --max-steps 200 --eval-interval "
             "100 --eval-episodes 2 --hidden 16,16 --hlc-max-steps 200 --hlc-workers 1 --quiet "
             "--wait 60 --held-out-episodes 2 --json-out " +
             results_file))
    args.push_back(word);
  const CliResult pipeline = run_pnpctl(dir, "pnpctl-pipeline", args);
  ASSERT_TRUE(pipeline.status && pipeline.status->ok()) << pipeline.out << pipeline.err;
  EXPECT_NE(pipeline.out.find("(seed 424242, gym/panda/block, arm hand)"), std::string::npos)
      << pipeline.out;
  const auto results = nlohmann::json::parse(read_file(results_file));
  EXPECT_EQ(results.at("actuation"), "arm");
  std::vector<std::string> order;
  std::map<std::string, long long> run_of, checkpoint_of;
  for (const auto& r : results.at("roles")) {
    order.push_back(r.at("role").get<std::string>());
    run_of[order.back()] = r.at("run_id").get<long long>();
    checkpoint_of[order.back()] = r.at("checkpoint_id").get<long long>();
  }
  EXPECT_EQ(order, (std::vector<std::string>{"retract", "manipulate", "approach", "hlc"}));
  for (auto& [role, server] : trainers) expect_clean_exit(*server);
  expect_clean_exit(inference);
  expect_clean_exit(sim);

  const StoreReader store(db);
  auto refs_of = [&](const std::string& role) {
    return nlohmann::json::parse(
               store.text("SELECT config_json FROM runs WHERE id = ?", {run_of[role]}))
        .at("checkpoints");
  };
  auto ids = [](const nlohmann::json& j) { return j.get<std::vector<long long>>(); };
  EXPECT_EQ(ids(refs_of("retract").at("successors")), std::vector<long long>{});
  EXPECT_EQ(ids(refs_of("manipulate").at("successors")),
            std::vector<long long>{checkpoint_of["retract"]});
  EXPECT_EQ(ids(refs_of("approach").at("successors")),
            (std::vector<long long>{checkpoint_of["manipulate"], checkpoint_of["retract"]}));
  for (const char* role : {"retract", "manipulate", "approach"}) {
    EXPECT_EQ(ids(refs_of(role).at("experts")), std::vector<long long>{}) << role;
    const auto spec = nlohmann::json::parse(
        store.text("SELECT config_json FROM runs WHERE id = ?", {run_of[role]}))["spec"];
    EXPECT_EQ(spec.at("actuation"), "arm") << role;
  }
}

TEST(Pipeline, PnpctlReportsTheServicesRefusalsAndNothingIsStored) {
  TempDir dir("pnpctl_refusals");
  ChildProcess trainer("train-approach", train_server("approach", dir.file("pnp.db")), dir.path());
  const int port = trainer.port();
  ASSERT_GT(port, 0) << trainer.diagnostics();
  const std::string prefix =
      "pnpctl: error: CreateTrainingRun (" + loopback(port) + "): INVALID_ARGUMENT: ";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"--updates-per-transition", "-0.4"},
       "updates_per_transition: expected a non-negative number (0: updates_per_cycle), got "
       "-0.400000"},
      {{"--hidden", "0"}, "hidden[0]: expected a width from 1 to 4096, got 0"},
      {{"--algo", "a3c"},
       "algorithm: expected one of ddpg_her, bc, bc_offline for a subtask expert, got \"a3c\""},
  };
  int k = 0;
  for (const auto& [flags, message] : cases) {
    std::vector<std::string> args{"--approach", loopback(port), "train",
                                  "--role",     "approach",     "--quiet"};
    args.insert(args.end(), flags.begin(), flags.end());
    const CliResult result = run_pnpctl(dir, "pnpctl-" + std::to_string(k++), args, 60s);
    ASSERT_TRUE(result.status) << message;
    EXPECT_EQ(result.status->describe(), "exit 2") << result.err;
    EXPECT_EQ(result.err, prefix + message + "\n");
    EXPECT_EQ(result.out, "");
  }
  expect_clean_exit(trainer);
  const StoreReader store(dir.file("pnp.db"));
  EXPECT_EQ(store.integer("SELECT COUNT(*) FROM runs"), 0);
  EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
}

// A detached run is cancelled by id: pnpctl finds its role through any training service
// and asks that role's service; Ctrl-C on a watching `pnpctl train` says how.
TEST(Pipeline, PnpctlCancelStopsARunAndCtrlCSaysHow) {
  TempDir dir("pnpctl_cancel");
  // One after the other: this test is about cancelling, not about two servers creating
  // one store at once (ServerProcess.ServicesStartedTogetherOnANewStoreAllServe).
  ChildProcess trainer("train-retract", train_server("retract", dir.file("pnp.db")), dir.path());
  const int port = trainer.port();
  ASSERT_GT(port, 0) << trainer.diagnostics();
  ChildProcess reader("train-approach", train_server("approach", dir.file("pnp.db")), dir.path());
  const int reader_port = reader.port();
  ASSERT_GT(reader_port, 0) << reader.diagnostics();
  const std::vector<std::string> endpoints{"--retract", loopback(port), "--approach",
                                           loopback(reader_port)};
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.begin(), endpoints.begin(), endpoints.end());
    return args;
  };
  const CliResult created =
      run_pnpctl(dir, "create",
                 with({"train", "--role", "retract", "--max-steps", "500000", "--detach"}), 60s);
  ASSERT_TRUE(created.status && created.status->ok()) << created.err;
  EXPECT_NE(created.out.find("run 1 created"), std::string::npos) << created.out;
  const CliResult cancelled = run_pnpctl(dir, "cancel", with({"cancel", "1"}), 60s);
  ASSERT_TRUE(cancelled.status && cancelled.status->ok()) << cancelled.err;
  EXPECT_NE(cancelled.out.find("run 1 (retract) cancelled"), std::string::npos) << cancelled.out;
  const CliResult listed = run_pnpctl(dir, "checkpoints", with({"checkpoints", "1"}), 60s);
  ASSERT_TRUE(listed.status && listed.status->ok()) << listed.err;
  EXPECT_EQ(listed.out.rfind("checkpoint  run  role", 0), 0u) << listed.out;
  const CliResult again = run_pnpctl(dir, "cancel-again", with({"cancel", "1"}), 60s);
  ASSERT_TRUE(again.status);
  EXPECT_NE(again.status->describe(), "exit 0") << "a finished run cannot be cancelled twice";

  std::vector<std::string> watch{bin("pnpctl")};
  for (const auto& a : with({"train", "--role", "retract", "--max-steps", "500000", "--quiet"}))
    watch.push_back(a);
  ChildProcess watching("watch", watch, dir.path());
  for (int i = 0; i < 200 && watching.stdout_text().find("created") == std::string::npos; ++i)
    std::this_thread::sleep_for(50ms);
  watching.send_signal(SIGINT);
  const auto ended = watching.wait(30s);
  ASSERT_TRUE(ended) << watching.diagnostics();
  EXPECT_EQ(ended->describe(), "exit 130");
  EXPECT_NE(watching.stderr_text().find("run 2 goes on on the server (pnpctl cancel 2 stops it)"),
            std::string::npos)
      << watching.diagnostics();
  const CliResult stop =
      run_pnpctl(dir, "cancel-2", with({"cancel", "2", "--via", "retract"}), 60s);
  EXPECT_TRUE(stop.status && stop.status->ok()) << stop.err;
  expect_clean_exit(trainer);
  expect_clean_exit(reader);
}

}  // namespace
}  // namespace pnp::integration
