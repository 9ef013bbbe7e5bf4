// Integration: the real server binaries, started on free loopback ports (port 0, the
// chosen port read from their stdout), called through real stubs, then stopped with
// SIGTERM: each must drain and exit 0.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"
#include "tests/integration/store_reader.h"

namespace {

using pnp::integration::ChildProcess;
using pnp::integration::StoreReader;
using pnp::integration::TempDir;
using namespace std::chrono_literals;

std::shared_ptr<grpc::Channel> channel(int port) {
  return grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                             grpc::InsecureChannelCredentials());
}

TEST(ServerProcess, SimServerServesAndDrainsOnSigterm) {
  TempDir dir("sim_server");
  ChildProcess server("sim", {PNP_BIN_DIR "/pnp-sim-server", "--address", "127.0.0.1:0"},
                      dir.path());
  const int port = server.port();
  ASSERT_GT(port, 0) << server.diagnostics();
  auto stub = pnp::sim::v1::SimulationService::NewStub(channel(port));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  pnp::sim::v1::GetEnvSpecRequest request;
  pnp::sim::v1::GetEnvSpecResponse response;
  request.set_robot(pnp::common::v1::ROBOT_PANDA);
  request.set_object(pnp::common::v1::OBJECT_SHAPE_BLOCK);
  ASSERT_TRUE(stub->GetEnvSpec(&context, request, &response).ok());
  EXPECT_EQ(response.observation().size(), 25);
  const auto status = server.terminate_and_wait();
  ASSERT_TRUE(status) << server.diagnostics();
  EXPECT_TRUE(status->ok()) << server.diagnostics();
}

// A second server on a port in use must not bind too (gRPC's SO_REUSEPORT would let it,
// and clients would then alternate between the two): it exits non-zero saying why.
TEST(ServerProcess, ASecondServerOnAPortInUseExitsNamingIt) {
  TempDir dir("port_in_use");
  ChildProcess first("first", {PNP_BIN_DIR "/pnp-sim-server", "--address", "127.0.0.1:0"},
                     dir.path());
  const int port = first.port();
  ASSERT_GT(port, 0) << first.diagnostics();
  const std::string address = "127.0.0.1:" + std::to_string(port);
  ChildProcess second("second", {PNP_BIN_DIR "/pnp-sim-server", "--address", address}, dir.path());
  const auto ended = second.wait(30s);
  ASSERT_TRUE(ended) << "the second server is still running: " << second.diagnostics();
  EXPECT_TRUE(ended->exited && ended->code != 0) << ended->describe();
  EXPECT_NE(second.stderr_text().find("cannot listen on " + address + ": Address already in use"),
            std::string::npos)
      << second.diagnostics();
  EXPECT_TRUE(first.running()) << "the first server must keep serving";
  const auto status = first.terminate_and_wait();
  ASSERT_TRUE(status) << first.diagnostics();
  EXPECT_TRUE(status->ok()) << first.diagnostics();
}

// An inference server's serving status, once it listens (empty if it never did or the
// call failed).
std::optional<pnp::policy::v1::GetServingStatusResponse> serving_status(ChildProcess& server) {
  const int port = server.port();
  if (port <= 0) return std::nullopt;
  auto stub = pnp::policy::v1::PolicyService::NewStub(channel(port));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  pnp::policy::v1::GetServingStatusResponse status;
  if (!stub->GetServingStatus(&context, {}, &status).ok()) return std::nullopt;
  return status;
}

// SIGTERM, then a drained exit with status 0.
void expect_clean_exit(ChildProcess& server) {
  const auto ended = server.terminate_and_wait();
  ASSERT_TRUE(ended) << server.diagnostics();
  EXPECT_TRUE(ended->ok()) << server.diagnostics();
}

TEST(ServerProcess, InferenceServerStartsOnAnEmptyStoreAndDrains) {
  TempDir dir("inference_server");
  {
    ChildProcess server("inference",
                        {PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db",
                         dir.file("pnp.db"), "--create-db"},
                        dir.path());
    const auto status = serving_status(server);
    ASSERT_TRUE(status) << server.diagnostics();
    EXPECT_FALSE(status->ready());
    expect_clean_exit(server);
  }
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "pnp.db"));
}

// The inference service only reads the store: it serves a file it may not write (its
// permissions bind when the tests do not run as root; the read-only connection is pinned
// by StoreTest.AReadOnlyOpenNeverWritesAndSaysSoWhenAskedTo) and it serves while another
// process holds the write lock.
TEST(ServerProcess, InferenceServesAReadOnlyStoreWhileAnotherProcessWrites) {
  TempDir dir("inference_read_only");
  const std::string db = dir.file("pnp.db");
  {
    pnp::store::RunStore store(db);
    pnp::store::import_hierarchy(store, PNP_SOURCE_DIR "/tests/data/panda_block", "panda", "block");
  }
  pnp::store::Database writer(db);
  writer.execute("BEGIN IMMEDIATE");  // another process's write lock, for the whole start
  std::filesystem::permissions(db, std::filesystem::perms::owner_read |
                                       std::filesystem::perms::group_read |
                                       std::filesystem::perms::others_read);
  ChildProcess server("inference",
                      {PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db", db},
                      dir.path());
  const auto status = serving_status(server);
  ASSERT_TRUE(status) << server.diagnostics();
  EXPECT_TRUE(status->ready()) << server.diagnostics();
  EXPECT_EQ(status->roles_size(), 4);
  writer.execute("ROLLBACK");
  expect_clean_exit(server);
}

// Another process promotes two hierarchies in turn, every 10 ms, while a client asks the
// inference service (reloading every 10 ms) for actions: every answer comes from one
// hierarchy, its choreographer and expert promoted together, never a mix.
TEST(ServerProcess, AClientNeverSeesAMixedHierarchyWhileAnotherProcessPromotes) {
  TempDir dir("promotion_race");
  const std::string db = dir.file("pnp.db");
  const std::string data = PNP_SOURCE_DIR "/tests/data/panda_block";
  std::vector<std::int64_t> first, second;
  {
    pnp::store::RunStore store(db);
    first = pnp::store::import_hierarchy(store, data, "panda", "block");
    second = pnp::store::import_hierarchy(store, data, "panda", "block");
  }
  ChildProcess server("inference",
                      {PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db", db,
                       "--reload-ms", "10"},
                      dir.path());
  const int port = server.port();
  ASSERT_GT(port, 0) << server.diagnostics();
  auto stub = pnp::policy::v1::PolicyService::NewStub(channel(port));
  std::atomic<bool> done{false};
  std::thread promoter([&] {
    pnp::store::RunStore writer(db);
    for (int k = 0; k < 150; ++k) {
      writer.promote(k % 2 == 0 ? first : second);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    done = true;
  });
  pnp::policy::v1::PredictRequest request;
  for (int i = 0; i < 25; ++i) request.mutable_observation()->add_values(0.1);
  request.mutable_goal()->set_x_m(0.1);
  request.mutable_goal()->set_y_m(0.1);
  request.mutable_goal()->set_z_m(0.1);
  const auto in = [](const std::vector<std::int64_t>& set, std::int64_t id) {
    return std::find(set.begin(), set.end(), id) != set.end();
  };
  int answers = 0, mixed = 0, from_first = 0, from_second = 0;
  while (!done) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    pnp::policy::v1::PredictResponse response;
    const auto status = stub->Predict(&context, request, &response);
    if (!status.ok()) continue;  // nothing served yet
    ++answers;
    const auto chooser = response.choreographer_checkpoint_id();
    const auto expert = response.expert_checkpoint_id();
    if (in(first, chooser) && in(first, expert))
      ++from_first;
    else if (in(second, chooser) && in(second, expert))
      ++from_second;
    else
      ++mixed;
  }
  promoter.join();
  EXPECT_EQ(mixed, 0) << answers << " answers";
  EXPECT_GT(from_first, 0);
  EXPECT_GT(from_second, 0) << "the promotions were served as they came";
  expect_clean_exit(server);
}

// The platform starts its services at once over one new store file: each creates the
// schema if it is missing, and exactly one must do it (a race here once left a service
// dead with "table runs already exists"). A few rounds, each on a fresh file.
TEST(ServerProcess, ServicesStartedTogetherOnANewStoreAllServe) {
  for (int round = 0; round < 3; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    TempDir dir("new_store");
    const std::string db = dir.file("pnp.db");
    std::vector<std::unique_ptr<ChildProcess>> servers;
    for (const char* role : {"approach", "manipulate", "retract", "hlc", "e2e"}) {
      servers.push_back(std::make_unique<ChildProcess>(
          std::string("train-") + role,
          std::vector<std::string>{PNP_BIN_DIR "/pnp-train-server", "--role", role, "--address",
                                   "127.0.0.1:0", "--db", db, "--threads", "1"},
          dir.path()));
    }
    servers.push_back(std::make_unique<ChildProcess>(
        "inference",
        std::vector<std::string>{PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0",
                                 "--db", db, "--create-db"},
        dir.path()));
    for (auto& server : servers) EXPECT_GT(server->port(), 0) << server->diagnostics();
    // Killed, not stopped: a SIGTERM this early can hit the signal gap pinned below.
    for (auto& server : servers) server->kill();
    for (auto& server : servers) {
      const auto ended = server->wait(60s);
      ASSERT_TRUE(ended) << server->diagnostics();
      EXPECT_EQ(ended->describe(), "signal 9")
          << "ended before it was killed: " << server->diagnostics();
    }
    const StoreReader store(db);
    EXPECT_EQ(store.integer("SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name IN "
                            "('runs', 'metrics', 'checkpoints', 'promotions')"),
              4);
    EXPECT_EQ(store.text("PRAGMA integrity_check"), "ok");
  }
}

// Hex mask of `field` ("SigBlk", "SigCgt") in a /proc status file; 0 if absent.
unsigned long long signal_mask(const std::string& status, const std::string& field) {
  const auto at = status.find(field + ":");
  if (at == std::string::npos) return 0;
  return std::stoull(status.substr(at + field.size() + 1), nullptr, 16);
}

// OpenBLAS starts its pool in a library constructor, before main, so no mask set in main
// reaches those threads: a SIGTERM landing on one would take the default action and kill
// the server mid-drain (seen once in ten startup rounds while servers blocked SIGTERM and
// waited in sigwait). The servers catch it with a handler instead: every thread must
// either block or catch it.
TEST(ServerProcess, NoThreadLeavesSigtermToItsDefaultAction) {
  TempDir dir("signal_masks");
  ChildProcess server("train",
                      {PNP_BIN_DIR "/pnp-train-server", "--role", "approach", "--address",
                       "127.0.0.1:0", "--db", dir.file("pnp.db"), "--threads", "1"},
                      dir.path());
  ASSERT_GT(server.port(), 0) << server.diagnostics();
  const unsigned long long sigterm = 1ULL << (SIGTERM - 1);
  const auto tasks = std::filesystem::path("/proc") / std::to_string(server.pid()) / "task";
  for (const auto& task : std::filesystem::directory_iterator(tasks)) {
    const std::string status = pnp::integration::read_file(task.path() / "status");
    if (status.empty()) continue;  // the thread has ended
    EXPECT_TRUE((signal_mask(status, "SigBlk") & sigterm) != 0 ||
                (signal_mask(status, "SigCgt") & sigterm) != 0)
        << "thread " << task.path().filename() << " takes SIGTERM's default action:\n"
        << status;
  }
}

}  // namespace
