// Integration: the real server binaries, started on free loopback ports (port 0, the
// chosen port read from their stdout), called through real stubs, then stopped with
// SIGTERM: each must drain and exit 0.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"

extern char** environ;

namespace {

// A child process with its stdout on a pipe; killed if the test ends early.
class ServerProcess {
 public:
  explicit ServerProcess(std::vector<std::string> args) {
    int out[2];
    if (pipe(out) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, out[0]);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0)
      throw std::runtime_error("cannot start " + args[0]);
    posix_spawn_file_actions_destroy(&actions);
    close(out[1]);
    stdout_ = fdopen(out[0], "r");
  }
  ~ServerProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (stdout_) fclose(stdout_);
  }
  int port() {  // the first stdout line
    int port = 0;
    if (std::fscanf(stdout_, "%d", &port) != 1) return 0;
    return port;
  }
  int terminate() {  // SIGTERM, then the exit status
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

 private:
  pid_t pid_ = -1;
  FILE* stdout_ = nullptr;
};

std::shared_ptr<grpc::Channel> channel(int port) {
  return grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                             grpc::InsecureChannelCredentials());
}

TEST(ServerProcess, SimServerServesAndDrainsOnSigterm) {
  ServerProcess server({PNP_BIN_DIR "/pnp-sim-server", "--address", "127.0.0.1:0"});
  const int port = server.port();
  ASSERT_GT(port, 0);
  auto stub = pnp::sim::v1::SimulationService::NewStub(channel(port));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  pnp::sim::v1::GetEnvSpecRequest request;
  pnp::sim::v1::GetEnvSpecResponse response;
  request.set_robot(pnp::common::v1::ROBOT_PANDA);
  request.set_object(pnp::common::v1::OBJECT_SHAPE_BLOCK);
  ASSERT_TRUE(stub->GetEnvSpec(&context, request, &response).ok());
  EXPECT_EQ(response.observation().size(), 25);
  EXPECT_EQ(server.terminate(), 0);
}

TEST(ServerProcess, InferenceServerStartsOnAnEmptyStoreAndDrains) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("pnp_integration_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  {
    ServerProcess server({PNP_BIN_DIR "/pnp-inference-server", "--address", "127.0.0.1:0", "--db",
                          (dir / "pnp.db").string()});
    const int port = server.port();
    ASSERT_GT(port, 0);
    auto stub = pnp::policy::v1::PolicyService::NewStub(channel(port));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    pnp::policy::v1::GetServingStatusResponse status;
    ASSERT_TRUE(stub->GetServingStatus(&context, {}, &status).ok());
    EXPECT_FALSE(status.ready());
    EXPECT_EQ(server.terminate(), 0);
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "pnp.db"));
  std::filesystem::remove_all(dir);
}

}  // namespace
