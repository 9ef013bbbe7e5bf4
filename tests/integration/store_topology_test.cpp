// Integration: the platform past one machine. Only pnp-store-server has the database; each
// other server runs in an empty directory of its own and reaches the store over gRPC.
// Inference replicas switch to a promotion made through any one of them, told by the store's
// WatchPromotions stream; a client that balances over the replicas (round_robin, retried
// Predict) rides out a replica killed under it; the dashboard reads the runs through it.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "services/common/replica_channel.h"
#include "services/store/remote_store.h"
#include "store/checkpoint_import.h"
#include "tests/integration/child_process.h"
#include "tests/integration/metrics_scrape.h"
#include "tests/integration/store_reader.h"

namespace pnp::integration {
namespace {

namespace pv1 = pnp::policy::v1;
constexpr auto kGuard = 60s;  // failure guard on every wait, never an expectation
// The pipeline's runs: long enough that the approach run can be caught between evaluations.
constexpr std::int64_t kPipelineSteps = 2000;
constexpr std::int64_t kEvalInterval = 200;

class Topology {
 public:
  explicit Topology(const std::string& name) : dir_(name) {
    std::filesystem::create_directories(dir_.path() / "store");
    db_ = (dir_.path() / "store" / "pnp.db").string();
    store_ = std::make_unique<ChildProcess>(
        "store",
        std::vector<std::string>{PNP_BIN_DIR "/pnp-store-server", "--address", "127.0.0.1:0",
                                 "--db", db_},
        dir_.path(), std::vector<std::pair<std::string, std::string>>{}, dir_.path() / "store");
    store_port_ = store_->port();
  }

  int store_port() const { return store_port_; }
  const std::string& db() const { return db_; }
  ChildProcess& store_process() { return *store_; }
  const TempDir& dir() const { return dir_; }

  // pnp-inference-server --store, in an empty directory of its own.
  std::unique_ptr<ChildProcess> inference(const std::string& name) {
    const auto own = dir_.path() / name;
    std::filesystem::create_directories(own);
    return std::make_unique<ChildProcess>(
        name,
        std::vector<std::string>{PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0",
                                 "--store", loopback(store_port_)},
        dir_.path(), std::vector<std::pair<std::string, std::string>>{}, own);
  }

  services::RemoteStore store_client() {
    return services::RemoteStore(
        grpc::CreateCustomChannel(loopback(store_port_), grpc::InsecureChannelCredentials(),
                                  services::store_channel_arguments()),
        loopback(store_port_));
  }

 private:
  TempDir dir_;
  std::string db_;
  std::unique_ptr<ChildProcess> store_;
  int store_port_ = 0;
};

std::unique_ptr<pv1::PolicyService::Stub> policy_stub(int port) {
  return pv1::PolicyService::NewStub(
      grpc::CreateChannel(loopback(port), grpc::InsecureChannelCredentials()));
}

// The checkpoint a replica serves for `role` (0: nothing yet, or unreachable).
std::int64_t served_role(pv1::PolicyService::Stub& stub, pnp::common::v1::Role role) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  pv1::GetServingStatusResponse status;
  if (!stub.GetServingStatus(&context, {}, &status).ok() || !status.ready()) return 0;
  for (const auto& served : status.roles())
    if (served.role() == role) return served.checkpoint_id();
  return 0;
}

std::int64_t served_hlc(pv1::PolicyService::Stub& stub) {
  return served_role(stub, pnp::common::v1::ROLE_HLC);
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

pv1::PredictRequest a_request() {
  pv1::PredictRequest request;
  for (int i = 0; i < 25; ++i) request.mutable_observation()->add_values(0.1);
  request.mutable_goal()->set_x_m(0.1);
  request.mutable_goal()->set_y_m(0.1);
  request.mutable_goal()->set_z_m(0.1);
  return request;
}

// A client balanced over the replicas on `port_a` and `port_b` (as pnpctl, the gateway
// and the dashboard dial inference) makes 600 predictions; `kill_one` runs before the 201st.
// None may fail: the killed replica's calls are retried on the other.
void expect_no_error_while_a_replica_dies(int port_a, int port_b,
                                          const std::function<void()>& kill_one) {
  grpc::ChannelArguments args;
  services::balance_over_replicas(args);
  const auto balanced = pv1::PolicyService::NewStub(grpc::CreateCustomChannel(
      "ipv4:127.0.0.1:" + std::to_string(port_a) + ",127.0.0.1:" + std::to_string(port_b),
      grpc::InsecureChannelCredentials(), args));
  const pv1::PredictRequest request = a_request();
  int answers = 0, errors = 0, answers_after_kill = 0;
  std::string first_error;
  bool killed = false;
  for (int k = 0; k < 600; ++k) {
    if (k == 200) {
      kill_one();
      killed = true;
    }
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    pv1::PredictResponse response;
    const grpc::Status status = balanced->Predict(&context, request, &response);
    if (status.ok()) {
      ++answers;
      if (killed) ++answers_after_kill;
    } else if (errors++ == 0) {
      first_error = std::to_string(status.error_code()) + " " + status.error_message();
    }
  }
  EXPECT_EQ(errors, 0) << first_error;
  EXPECT_EQ(answers_after_kill, 400);
  EXPECT_EQ(answers, 600);
}

// The robot controller has no store of its own: with --store its audit (every robot call)
// lands in the platform's one table, with the lease id redacted.
TEST(StoreTopology, TheRobotControllersAuditReachesTheStore) {
  Topology topology("store_topology_robot_audit");
  const auto own = topology.dir().path() / "robot-sim";
  std::filesystem::create_directories(own);
  ChildProcess robot("robot-sim",
                     {PNP_BIN_DIR "/pnp-robot-sim", "--address", "127.0.0.1:0", "--clock",
                      "lockstep", "--store", loopback(topology.store_port())},
                     topology.dir().path(), std::vector<std::pair<std::string, std::string>>{},
                     own);
  ASSERT_GT(robot.port(), 0) << robot.diagnostics();
  auto stub = robot::v1::RobotControllerService::NewStub(
      grpc::CreateChannel(loopback(robot.port()), grpc::InsecureChannelCredentials()));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kGuard);
  robot::v1::AcquireLeaseRequest request;
  request.set_client_name("audited");
  robot::v1::AcquireLeaseResponse response;
  ASSERT_TRUE(stub->AcquireLease(&context, request, &response).ok());
  ASSERT_TRUE(wait_until(
      [&] {
        return StoreReader(topology.db())
                   .text(
                       "SELECT COUNT(*) FROM audit WHERE service = 'robot_sim' AND rpc LIKE "
                       "'%/AcquireLease' AND code = 'OK'") == "1";
      },
      kGuard, 20ms))
      << robot.diagnostics();
  EXPECT_EQ(
      StoreReader(topology.db())
          .text("SELECT COUNT(*) FROM audit WHERE request LIKE '%" + response.lease_id() + "%'"),
      "0")
      << "a lease id was written to the audit";
  EXPECT_TRUE(std::filesystem::is_empty(own)) << "the controller wrote a file of its own";
}

TEST(StoreTopology, InferenceReplicasFollowAPromotionAndABalancedClientRidesOutAKilledOne) {
  Topology topology("store_topology_inference");
  ASSERT_GT(topology.store_port(), 0) << topology.store_process().diagnostics();
  const auto data = std::filesystem::path(PNP_SOURCE_DIR) / "tests" / "data" / "panda_block";
  {
    services::RemoteStore store = topology.store_client();
    store::import_hierarchy(store, data, "panda", "block");
  }
  auto a = topology.inference("inference-a");
  auto b = topology.inference("inference-b");
  const int port_a = a->port(), port_b = b->port();
  ASSERT_GT(port_a, 0) << a->diagnostics();
  ASSERT_GT(port_b, 0) << b->diagnostics();
  auto stub_a = policy_stub(port_a), stub_b = policy_stub(port_b);
  ASSERT_TRUE(
      wait_until([&] { return served_hlc(*stub_a) > 0 && served_hlc(*stub_b) > 0; }, kGuard, 20ms))
      << a->diagnostics() << b->diagnostics();

  // A new hierarchy, promoted through replica A: B switches when the store says so.
  std::vector<std::int64_t> fresh;
  {
    services::RemoteStore store = topology.store_client();
    for (const char* role : {"approach", "manipulate", "retract", "hlc"}) {
      fresh.push_back(
          store::import_checkpoint(store,
                                   {role, std::string(role) == "hlc" ? "a3c" : "ddpg_her", "panda",
                                    "block", data / (std::string(role) + ".ckpt")},
                                   false));
    }
  }
  grpc::ClientContext promote_context;
  pv1::PromoteCheckpointRequest promote;
  for (const auto id : fresh) promote.add_checkpoint_ids(id);
  pv1::PromoteCheckpointResponse promoted;
  const auto promoted_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(stub_a->PromoteCheckpoint(&promote_context, promote, &promoted).ok());
  ASSERT_TRUE(wait_until([&] { return served_hlc(*stub_b) == fresh.back(); }, kGuard, 5ms))
      << b->diagnostics();
  std::printf(
      "[ measured ] replica B served the promotion made through A after %.0f ms\n",
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - promoted_at)
          .count());
  EXPECT_EQ(served_hlc(*stub_a), fresh.back());
  // The promotion is in the store's audit trail, written by replica A through the store
  // server, and an operator reads it back from there.
  ASSERT_TRUE(wait_until(
      [&] {
        return StoreReader(topology.db())
                   .text(
                       "SELECT COUNT(*) FROM audit WHERE service = 'inference' AND rpc LIKE "
                       "'%/PromoteCheckpoint' AND code = 'OK'") == "1";
      },
      kGuard, 20ms));
  ChildProcess audit(
      "pnpctl-audit",
      {PNP_BIN_DIR "/pnpctl", "audit", "--store", loopback(topology.store_port()), "--json"},
      topology.dir().path());
  const auto audited = audit.wait(kGuard);
  ASSERT_TRUE(audited && audited->ok()) << audit.stderr_text();
  EXPECT_NE(audit.stdout_text().find("PromoteCheckpoint"), std::string::npos)
      << audit.stdout_text();

  // A client balanced over both replicas (as pnpctl, the gateway and the dashboard dial
  // inference) predicts while replica A is killed.
  expect_no_error_while_a_replica_dies(port_a, port_b, [&] { a->kill(); });
  // The dashboard reads the runs through the store server too.
  const auto dashboard_dir = topology.dir().path() / "dashboard";
  std::filesystem::create_directories(dashboard_dir);
  ChildProcess dashboard(
      "dashboard",
      {PNP_BIN_DIR "/pnp-dashboard", "--address", "127.0.0.1:0", "--store",
       loopback(topology.store_port()), "--sim", "127.0.0.1:1", "--inference", loopback(port_b)},
      topology.dir().path(), {}, dashboard_dir);
  const int dashboard_port = dashboard.port();
  ASSERT_GT(dashboard_port, 0) << dashboard.diagnostics();
  const std::string runs = http_get(dashboard_port, "/api/runs");
  EXPECT_NE(runs.find("200 OK"), std::string::npos) << runs;
  EXPECT_EQ(count_of(runs, "\"role\":\"hlc\""), 2) << runs;  // imported, then fresh

  // Nothing but the store server has a file.
  for (const char* name : {"inference-a", "inference-b", "dashboard"})
    EXPECT_TRUE(std::filesystem::is_empty(topology.dir().path() / name)) << name;

  // A store server that stops ends the replicas' watches itself (they reconnect to the
  // next one), rather than leaving them to be cut at the end of its grace.
  const auto stopped = topology.store_process().terminate_and_wait(kGuard);
  ASSERT_TRUE(stopped && stopped->ok()) << topology.store_process().diagnostics();
  EXPECT_TRUE(wait_until(
      [&] { return b->stderr_text().find("the store server is stopping") != std::string::npos; },
      kGuard, 20ms))
      << b->diagnostics();
}

// The pid in a training server's owner name ("host:pid:started_ms").
pid_t owner_pid(const std::string& owner) {
  const auto first = owner.find(':');
  const auto second = owner.find(':', first + 1);
  if (first == std::string::npos || second == std::string::npos) return 0;
  return static_cast<pid_t>(std::stol(owner.substr(first + 1, second - first - 1)));
}

// The whole platform as separate processes, each in an empty directory of its own: the
// store server (the only one with a file), two simulation servers (one pool target for
// the trainers), two training servers of the approach role and one of each other role
// (all on the store server), two inference replicas. `pnpctl pipeline` trains, promotes
// and evaluates through them, addressing each replicated tier as one target. Mid-way
// through the approach run, the replica that owns it is SIGKILLed: the other takes it over
// from its last checkpoint and the pipeline goes on; its curve has every evaluation once,
// in order. Then an inference replica is SIGKILLed under a balanced client, and a
// promotion reaches the survivor.
TEST(StoreTopology, PnpctlPipelineRunsThroughAPlatformWithNoSharedFileAndRidesOutKilledReplicas) {
  Topology topology("store_topology_pipeline");
  ASSERT_GT(topology.store_port(), 0) << topology.store_process().diagnostics();
  const std::string store = loopback(topology.store_port());
  const auto own_dir = [&](const std::string& name) {
    const auto path = topology.dir().path() / name;
    std::filesystem::create_directories(path);
    return path;
  };
  const auto start = [&](const std::string& name, std::vector<std::string> args) {
    return std::make_unique<ChildProcess>(name, std::move(args), topology.dir().path(),
                                          std::vector<std::pair<std::string, std::string>>{},
                                          own_dir(name));
  };
  // One target per tier: a replicated one names every replica (as a DNS name would).
  const auto targets = [](const std::vector<int>& ports) {
    std::string target = "ipv4:";
    for (std::size_t k = 0; k < ports.size(); ++k)
      target += (k ? "," : "") + std::string("127.0.0.1:") + std::to_string(ports[k]);
    return target;
  };
  std::vector<std::unique_ptr<ChildProcess>> sims;
  std::vector<int> sim_ports;
  for (const char* name : {"sim-1", "sim-2"}) {
    sims.push_back(start(name, {PNP_BIN_DIR "/pnp-sim-server", "--address", "127.0.0.1:0"}));
    sim_ports.push_back(sims.back()->port());
    ASSERT_GT(sim_ports.back(), 0) << sims.back()->diagnostics();
  }
  std::map<std::string, std::vector<int>> trainer_ports;
  std::vector<std::unique_ptr<ChildProcess>> trainers;
  for (const std::string role : {"approach", "approach", "manipulate", "retract", "hlc"}) {
    trainers.push_back(start(
        "train-" + role + "-" + std::to_string(trainer_ports[role].size() + 1),
        {PNP_BIN_DIR "/pnp-train-server", "--role", role, "--address", "127.0.0.1:0", "--threads",
         "1", "--store", store, "--sim-address", targets(sim_ports), "--run-lease-s", "1"}));
    const int port = trainers.back()->port();
    ASSERT_GT(port, 0) << trainers.back()->diagnostics();
    trainer_ports[role].push_back(port);
  }
  auto a = topology.inference("inference-a");
  auto b = topology.inference("inference-b");
  ASSERT_GT(a->port(), 0) << a->diagnostics();
  ASSERT_GT(b->port(), 0) << b->diagnostics();
  // The store server answers the probe the deployments use.
  ChildProcess probe("pnpctl-health-store",
                     {PNP_BIN_DIR "/pnpctl", "--store", store, "health", "--only", "store"},
                     topology.dir().path(), {}, own_dir("pnpctl"));
  const auto probed = probe.wait(kGuard);
  ASSERT_TRUE(probed && probed->ok()) << probe.stdout_text() << probe.stderr_text();
  EXPECT_NE(probe.stdout_text().find("SERVING"), std::string::npos) << probe.stdout_text();
  std::vector<std::string> args{PNP_BIN_DIR "/pnpctl",
                                "--sim",
                                targets(sim_ports),
                                "--approach",
                                targets(trainer_ports["approach"]),
                                "--manipulate",
                                targets(trainer_ports["manipulate"]),
                                "--retract",
                                targets(trainer_ports["retract"]),
                                "--hlc",
                                targets(trainer_ports["hlc"]),
                                "--e2e",
                                "127.0.0.1:1",
                                "--inference",
                                targets({a->port(), b->port()}),
                                "pipeline",
                                "--seed",
                                "1",
                                "--max-steps",
                                std::to_string(kPipelineSteps),
                                "--eval-interval",
                                std::to_string(kEvalInterval),
                                "--eval-episodes",
                                "4",
                                "--hidden",
                                "16,16",
                                "--hlc-max-steps",
                                "300",
                                "--hlc-workers",
                                "1",
                                "--wait",
                                "60",
                                "--held-out-episodes",
                                "3"};
  // The second approach replica is paused until the first has claimed the approach run, so
  // that the one killed is the one pnpctl watches the run through (the first of its
  // target): the watch must move to the other replica as the run does.
  ChildProcess& approach_1 = *trainers[0];
  ChildProcess& approach_2 = *trainers[1];
  approach_2.send_signal(SIGSTOP);
  ChildProcess pipeline("pnpctl-pipeline", args, topology.dir().path(), {}, own_dir("pnpctl"));

  // The approach run, once it has an evaluation: SIGKILL the replica that owns it.
  std::int64_t run_id = 0;
  std::string owner;
  ASSERT_TRUE(wait_until(
      [&] {
        const auto rows =
            StoreReader(topology.db())
                .rows(
                    "SELECT id, owner FROM runs WHERE role = 'approach' AND state = 'running' AND "
                    "(SELECT COUNT(*) FROM metrics WHERE metrics.run_id = runs.id) >= 1");
        if (rows.empty()) return false;
        run_id = std::stoll(rows[0][0]);
        owner = rows[0][1];
        return true;
      },
      kGuard, 5ms))
      << pipeline.stderr_text();
  ASSERT_EQ(owner_pid(owner), approach_1.pid()) << owner;
  approach_2.send_signal(SIGCONT);
  approach_1.kill();
  const auto killed_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until(
      [&] {
        const std::string now =
            StoreReader(topology.db())
                .text("SELECT COALESCE(owner, '') FROM runs WHERE id = ?", {run_id});
        return !now.empty() && now != owner;
      },
      kGuard, 5ms));
  std::printf("[ measured ] the other approach replica took the run over %.2f s after the kill\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count());

  const auto status = pipeline.wait(300s);
  ASSERT_TRUE(status && status->ok()) << pipeline.stdout_text() << pipeline.stderr_text();
  EXPECT_NE(pipeline.stdout_text().find("held-out through the services"), std::string::npos)
      << pipeline.stdout_text();
  EXPECT_NE(pipeline.stderr_text().find("watching run " + std::to_string(run_id) + " again"),
            std::string::npos)
      << pipeline.stderr_text();
  // The run finished, every evaluation once and in order, checkpoints in step order.
  {
    const StoreReader db(topology.db());
    EXPECT_EQ(db.text("PRAGMA integrity_check"), "ok");
    EXPECT_EQ(db.text("SELECT state FROM runs WHERE id = ?", {run_id}), "succeeded");
    std::vector<std::int64_t> steps;
    for (const auto& row :
         db.rows("SELECT env_steps FROM metrics WHERE run_id = ? ORDER BY rowid", {run_id}))
      steps.push_back(std::stoll(row[0]));
    ASSERT_FALSE(steps.empty());
    EXPECT_GE(steps.back(), kPipelineSteps);
    // One evaluation per interval, in order (a resumed run evaluates at the first step
    // past each boundary, which may overshoot it by part of an episode).
    ASSERT_EQ(steps.size(), static_cast<std::size_t>(kPipelineSteps / kEvalInterval))
        << "evaluations lost or repeated";
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const auto boundary = static_cast<std::int64_t>(k + 1) * kEvalInterval;
      EXPECT_TRUE(steps[k] >= boundary && steps[k] < boundary + kEvalInterval)
          << "evaluation " << k << " of run " << run_id << " at " << steps[k] << " steps";
    }
    EXPECT_EQ(
        db.rows("SELECT env_steps FROM checkpoints WHERE run_id = ? ORDER BY id", {run_id}),
        db.rows("SELECT env_steps FROM checkpoints WHERE run_id = ? ORDER BY env_steps", {run_id}));
  }
  // Both replicas serve what the pipeline promoted.
  auto stub_a = policy_stub(a->port()), stub_b = policy_stub(b->port());
  EXPECT_TRUE(wait_until(
      [&] { return served_hlc(*stub_a) > 0 && served_hlc(*stub_a) == served_hlc(*stub_b); }, kGuard,
      20ms));
  for (const auto& trainer : trainers) {
    if (trainer.get() != &approach_1) {
      EXPECT_TRUE(std::filesystem::is_empty(topology.dir().path() / trainer->name()))
          << trainer->name() << " wrote a file";
    }
  }
  for (const char* name : {"sim-1", "sim-2", "inference-a", "inference-b", "pnpctl"})
    EXPECT_TRUE(std::filesystem::is_empty(topology.dir().path() / name)) << name << " wrote a file";

  // A balanced client predicts while replica A is SIGKILLed; then a promotion (the
  // approach run's first checkpoint, from before the takeover) reaches the survivor.
  expect_no_error_while_a_replica_dies(a->port(), b->port(), [&] { a->kill(); });
  services::RemoteStore remote = topology.store_client();
  const auto first_checkpoint = remote.checkpoints(run_id).front().id;
  const auto promoted_at = std::chrono::steady_clock::now();
  remote.promote(first_checkpoint);
  ASSERT_TRUE(wait_until(
      [&] { return served_role(*stub_b, pnp::common::v1::ROLE_APPROACH) == first_checkpoint; },
      kGuard, 5ms))
      << b->diagnostics();
  std::printf(
      "[ measured ] the surviving replica served a promotion after %.0f ms\n",
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - promoted_at)
          .count());
}

}  // namespace
}  // namespace pnp::integration
