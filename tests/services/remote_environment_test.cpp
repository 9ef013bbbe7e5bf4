// Rollouts on simulation services: RemoteEnvironment against the core's PickPlaceEnv, and
// training through RemoteEnvFactory against training in process. Real services on
// loopback ports, real stubs.
#include "clients/sim_client/remote_environment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "clients/sim_client/remote_env_factory.h"
#include "clients/sim_client/sim_target.h"
#include "common/error.h"
#include "services/common/server_runtime.h"
#include "services/sim/sim_service.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_expert.h"
#include "support/refusal.h"
#include "tests/core/training/small_runs.h"
#include "training/role_training.h"

namespace pnp::sim_client {
namespace {

using std::chrono::milliseconds;

// A simulation service in this process on a free loopback port.
class SimServer {
 public:
  SimServer()
      : runtime_(services::ServerConfig{
            "127.0.0.1:0", 4 << 20, {&service_}, {"pnp.sim.v1.SimulationService"}}) {}
  ~SimServer() { stop(); }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  double env_steps() {
    return metrics_
        .counter("pnp_env_steps_total", "Environment steps executed (Step and StreamRollout).")
        .Value();
  }
  void stop() {
    if (!stopped_) runtime_.shutdown(milliseconds(100));
    stopped_ = true;
  }

 private:
  services::MetricsRegistry metrics_;
  services::SimServiceImpl service_{&metrics_};
  services::ServerRuntime runtime_;
  int port_ = runtime_.port();
  bool stopped_ = false;
};

using pnp::testing::code_of;

// In every world profile: the service builds the world the request names.
class RemoteEnvironmentInWorld : public ::testing::TestWithParam<sim::WorldProfile> {};

TEST_P(RemoteEnvironmentInWorld, ScriptedEpisodesMatchTheCoreBitForBit) {
  SimServer server;
  const RemoteEnvFactory factory({server.address()}, sim::Robot::kFetch, sim::ObjectShape::kBlock,
                                 GetParam());
  const auto remote = factory.make();
  sim::PickPlaceEnv local(
      sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock, GetParam()));
  for (std::uint64_t seed : {4u, 5u}) {  // two episodes on the same remote environment
    remote->reset(seed);
    local.reset(seed);
    ASSERT_EQ(remote->observation(), local.observation());
    ASSERT_EQ(remote->episode_goal(), local.episode_goal());
    sim::Subtask subtask = sim::Subtask::kApproach;
    bool success = false;
    while (!local.needs_reset()) {
      const sim::TaskState state = local.task_state();
      if (subtask != sim::Subtask::kRetract &&
          sim::objective_done(sim::objective_of(subtask), state))
        subtask = sim::kAllSubtasks[static_cast<std::size_t>(subtask) + 1];
      const sim::Objective objective = sim::objective_of(subtask);
      const sim::Goal goal = sim::objective_goal(objective, state);
      const sim::Action action = sim::scripted_action(subtask, state);
      const sim::StepResult a = remote->step(action, goal, objective);
      const sim::StepResult b = local.step(action, goal, objective);
      ASSERT_EQ(a.observation, b.observation) << "step " << local.elapsed_steps();
      EXPECT_EQ(a.achieved_goal, b.achieved_goal);
      EXPECT_EQ(a.reward, b.reward);
      EXPECT_EQ(a.objective_done, b.objective_done);
      EXPECT_EQ(a.episode_over, b.episode_over);
      EXPECT_EQ(remote->elapsed_steps(), local.elapsed_steps());
      success = b.task_success;
    }
    EXPECT_TRUE(remote->needs_reset());
    EXPECT_TRUE(success) << "the scripted pipeline places the object";
  }
}

INSTANTIATE_TEST_SUITE_P(Worlds, RemoteEnvironmentInWorld,
                         ::testing::Values(sim::WorldProfile::kPaper, sim::WorldProfile::kGym),
                         [](const auto& world) {
                           return std::string(sim::world_profile_name(world.param));
                         });

TEST(RemoteEnvironment, RefusesBadInputBeforeSendingIt) {
  SimServer server;
  const RemoteEnvFactory factory({server.address()}, sim::Robot::kFetch, sim::ObjectShape::kBlock);
  const auto env = factory.make();
  const sim::Goal goal = sim::Goal::Zero();
  EXPECT_EQ(code_of([&] { env->step(sim::Action::Zero(), goal, sim::Objective::kTask); }),
            ErrorCode::kFailedPrecondition);
  env->reset(1);
  sim::Action nan = sim::Action::Zero();
  nan(2) = std::numeric_limits<double>::quiet_NaN();
  std::string message;
  EXPECT_EQ(code_of([&] { env->step(nan, goal, sim::Objective::kTask); }, &message),
            ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("action"), std::string::npos) << message;
  // Nothing was sent: the environment still works.
  EXPECT_EQ(env->elapsed_steps(), 0);
  env->step(sim::Action::Zero(), goal, sim::Objective::kTask);
  EXPECT_EQ(env->elapsed_steps(), 1);
}

TEST(RemoteEnvironment, AnUnreachableServiceIsUnavailableNamingItsAddress) {
  int port = 0;
  {
    SimServer gone;  // a port that was free a moment ago and has nothing behind it now
    port = std::stoi(gone.address().substr(gone.address().rfind(':') + 1));
  }
  const std::string address = "127.0.0.1:" + std::to_string(port);
  const RemoteEnvFactory factory({address}, sim::Robot::kFetch, sim::ObjectShape::kBlock,
                                 sim::WorldProfile::kPaper, sim::Actuation::kMocap, {},
                                 milliseconds(300));
  std::string message;
  EXPECT_EQ(code_of([&] { factory.make(); }, &message), ErrorCode::kUnavailable);
  EXPECT_NE(message.find(address), std::string::npos) << message;
}

TEST(RemoteEnvironment, AServiceLostMidEpisodeIsUnavailable) {
  auto server = std::make_unique<SimServer>();
  const RemoteEnvFactory factory({server->address()}, sim::Robot::kFetch, sim::ObjectShape::kBlock);
  const auto env = factory.make();
  env->reset(2);
  env->step(sim::Action::Zero(), sim::Goal::Zero(), sim::Objective::kTask);
  server->stop();
  EXPECT_EQ(
      code_of([&] { env->step(sim::Action::Zero(), sim::Goal::Zero(), sim::Objective::kTask); }),
      ErrorCode::kUnavailable);
  EXPECT_EQ(code_of([&] { env->reset(3); }), ErrorCode::kUnavailable);
}

TEST(RemoteEnvFactory, RefusesAnEmptyAddressList) {
  std::string message;
  EXPECT_EQ(code_of([&] { RemoteEnvFactory({}, sim::Robot::kFetch, sim::ObjectShape::kBlock); },
                    &message),
            ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("sim_address"), std::string::npos) << message;
}

TEST(SimTarget, NamesOneServerAPoolOrAResolvedName) {
  using V = std::vector<SimServerAddress>;
  EXPECT_EQ(resolve_sim_target("sim:50051"), (V{{"sim:50051", ""}}));
  EXPECT_EQ(resolve_sim_target("ipv4:127.0.0.1:7,127.0.0.1:5,127.0.0.1:7"),
            (V{{"ipv4:127.0.0.1:5", ""}, {"ipv4:127.0.0.1:7", ""}}));
  EXPECT_EQ(resolve_sim_target("ipv6:[::1]:9"), (V{{"ipv6:[::1]:9", ""}}));
  // A name stands for every address it resolves to, each verified against the name.
  const V localhost = resolve_sim_target("dns:///localhost:50051");
  ASSERT_FALSE(localhost.empty());
  for (const SimServerAddress& server : localhost) {
    EXPECT_TRUE(server.address == "ipv4:127.0.0.1:50051" || server.address == "ipv6:[::1]:50051")
        << server.address;
    EXPECT_EQ(server.server_name, "localhost");
  }
}

TEST(SimTarget, RefusesMalformedTargetsNamingTheField) {
  for (const std::string target :
       {"", "sim", "sim:port", "dns://8.8.8.8/sim:1", "dns:///", "dns:sim:1",
        "ipv4:", "ipv4:127.0.0.1", "ipv4:127.0.0.1:1,", "ipv6:[::1]", "ipv4:sim:50051",
        "ipv6:::1:5", "ipv4:[::1]:5", "ipv6:[127.0.0.1]:5"}) {
    std::string message;
    EXPECT_EQ(code_of([&] { resolve_sim_target(target); }, &message), ErrorCode::kInvalidArgument)
        << target;
    EXPECT_NE(message.find("sim_address"), std::string::npos) << message;
  }
  EXPECT_EQ(code_of([&] {
              RemoteEnvFactory({"ipv4:127.0.0.1"}, sim::Robot::kFetch, sim::ObjectShape::kBlock);
            }),
            ErrorCode::kInvalidArgument);
}

// One target for a pool: environments alternate over its servers, and a server that is
// gone passes its turn instead of failing the run.
TEST(RemoteEnvFactory, APoolTargetSpreadsEnvironmentsAndSkipsAServerThatIsGone) {
  SimServer a, b;
  int gone_port = 0;
  {
    SimServer gone;
    gone_port = std::stoi(gone.address().substr(gone.address().rfind(':') + 1));
  }
  auto port_of = [](const std::string& address) { return address.substr(address.rfind(':') + 1); };
  const std::string pool = "ipv4:127.0.0.1:" + port_of(a.address()) +
                           ",127.0.0.1:" + port_of(b.address()) +
                           ",127.0.0.1:" + std::to_string(gone_port);
  const RemoteEnvFactory factory({pool}, sim::Robot::kFetch, sim::ObjectShape::kBlock,
                                 sim::WorldProfile::kPaper, sim::Actuation::kMocap, {},
                                 milliseconds(300));
  std::vector<std::unique_ptr<sim::Environment>> envs;
  for (int i = 0; i < 6; ++i) {
    envs.push_back(factory.make());
    envs.back()->reset(static_cast<std::uint64_t>(i));
    envs.back()->step(sim::Action::Zero(), sim::Goal::Zero(), sim::Objective::kTask);
  }
  // Two turns of three: the gone server's turns went to the next live one.
  EXPECT_GT(a.env_steps(), 0);
  EXPECT_GT(b.env_steps(), 0);
  EXPECT_EQ(a.env_steps() + b.env_steps(), 6);
  // With every server gone, the error is the first one's, naming its address.
  a.stop();
  b.stop();
  std::string message;
  EXPECT_EQ(code_of([&] { factory.make(); }, &message), ErrorCode::kUnavailable);
  EXPECT_NE(message.find("127.0.0.1:"), std::string::npos) << message;
}

// The acceptance test of scale-out: the same run on two remote services and in process
// gives the same learning curve and the same weights, bit for bit.
TEST(RemoteTraining, TwoServicesTrainExactlyAsInProcess) {
  SimServer a, b;
  auto run = [](const training::EnvironmentSource& environments) {
    training::TrainingHooks hooks;
    hooks.threads = 2;
    hooks.environments = environments;
    return training::train_role(training::testing::small_spec("approach", 400), {}, hooks, "test");
  };
  const auto local = run({});
  const std::vector<std::string> addresses{a.address(), b.address()};
  const auto remote = run([&](sim::Robot robot, sim::ObjectShape object, sim::WorldProfile world,
                              sim::Actuation actuation) {
    return std::make_unique<RemoteEnvFactory>(addresses, robot, object, world, actuation);
  });
  ASSERT_EQ(local.result.curve.size(), remote.result.curve.size());
  ASSERT_FALSE(local.result.curve.empty());
  for (std::size_t i = 0; i < local.result.curve.size(); ++i) {
    EXPECT_EQ(local.result.curve[i].env_steps, remote.result.curve[i].env_steps);
    EXPECT_EQ(local.result.curve[i].task_success, remote.result.curve[i].task_success);
    EXPECT_EQ(local.result.curve[i].subtask_success, remote.result.curve[i].subtask_success);
    EXPECT_EQ(local.result.curve[i].critic_loss, remote.result.curve[i].critic_loss);
  }
  EXPECT_EQ(local.result.train_env_steps, remote.result.train_env_steps);
  // Every step, training and evaluation, ran on the two services, shared between them.
  EXPECT_GT(a.env_steps(), 0);
  EXPECT_GT(b.env_steps(), 0);
  EXPECT_EQ(a.env_steps() + b.env_steps(),
            static_cast<double>(remote.result.train_env_steps + remote.result.eval_env_steps));
  EXPECT_TRUE(local.checkpoint == remote.checkpoint) << "the weights differ";
}

}  // namespace
}  // namespace pnp::sim_client
