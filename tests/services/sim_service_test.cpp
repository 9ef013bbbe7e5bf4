// In-process gRPC tests of SimulationService through a real stub on a loopback port.
#include "services/sim/sim_service.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/error.h"
#include "common/rng.h"
#include "services/common/server_runtime.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_expert.h"
#include "sim/world_layout.h"

namespace pnp::services {
namespace {

namespace sv1 = pnp::sim::v1;

class SimServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    runtime_ = std::make_unique<ServerRuntime>(
        ServerConfig{"127.0.0.1:0", 4 << 20, {&service_}, {"pnp.sim.v1.SimulationService"}});
    stub_ = sv1::SimulationService::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string(runtime_->port()), grpc::InsecureChannelCredentials()));
  }
  void TearDown() override { runtime_->shutdown(std::chrono::milliseconds(500)); }

  std::string create(int count, std::uint64_t seed = 5) {
    grpc::ClientContext c;
    sv1::CreateEnvRequest r;
    sv1::CreateEnvResponse out;
    r.set_robot(common::v1::ROBOT_FETCH);
    r.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    r.set_seed(seed);
    r.set_count(count);
    EXPECT_TRUE(stub_->CreateEnv(&c, r, &out).ok());
    return out.env_id();
  }
  sv1::ResetResponse reset(const std::string& id) {
    grpc::ClientContext c;
    sv1::ResetRequest r;
    sv1::ResetResponse out;
    r.set_env_id(id);
    EXPECT_TRUE(stub_->Reset(&c, r, &out).ok());
    return out;
  }
  grpc::Status step(const sv1::StepRequest& r, sv1::StepResponse& out) {
    grpc::ClientContext c;
    return stub_->Step(&c, r, &out);
  }
  static void add_action(sv1::StepRequest& r, int index, double dx, const Eigen::Vector3d& goal) {
    auto* a = r.add_actions();
    a->set_index(index);
    a->mutable_action()->set_dx(dx);
    a->mutable_goal()->set_x_m(goal.x());
    a->mutable_goal()->set_y_m(goal.y());
    a->mutable_goal()->set_z_m(goal.z());
    a->set_objective(sv1::OBJECTIVE_TASK);
  }

  SimServiceImpl service_;
  std::unique_ptr<ServerRuntime> runtime_;
  std::unique_ptr<sv1::SimulationService::Stub> stub_;
};

TEST_F(SimServiceTest, TheSameSeedGivesTheSameEpisodesAsTheCore) {
  const auto a = reset(create(2, 9));
  const auto b = reset(create(2, 9));
  ASSERT_EQ(a.states_size(), 2);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(a.states(k).episode_goal().x_m(), b.states(k).episode_goal().x_m());
    // Environment k's first episode is the core's episode derive_seed(derive_seed(9, k), 0).
    pnp::sim::PickPlaceEnv env(
        pnp::sim::WorldModel::load(pnp::sim::Robot::kFetch, pnp::sim::ObjectShape::kBlock,
                                   pnp::sim::kDefaultWorldProfile));  // unset world: default
    env.reset(derive_seed(derive_seed(9, static_cast<std::uint64_t>(k)), 0));
    EXPECT_EQ(a.states(k).episode_goal().y_m(), env.episode_goal().y());
    EXPECT_EQ(a.states(k).observation().values(3), env.observation()(3));
  }
  EXPECT_NE(a.states(0).episode_goal().x_m(), a.states(1).episode_goal().x_m());
}

TEST_F(SimServiceTest, ExplicitEpisodeSeedsGiveTheCoresEpisodes) {
  const std::string id = create(3);
  grpc::ClientContext c;
  sv1::ResetRequest r;
  sv1::ResetResponse out;
  r.set_env_id(id);
  r.add_indices(2);
  r.add_indices(0);
  r.add_episode_seeds(11);
  r.add_episode_seeds(12);
  ASSERT_TRUE(stub_->Reset(&c, r, &out).ok());
  ASSERT_EQ(out.states_size(), 2);
  pnp::sim::PickPlaceEnv env(
      pnp::sim::WorldModel::load(pnp::sim::Robot::kFetch, pnp::sim::ObjectShape::kBlock,
                                 pnp::sim::kDefaultWorldProfile));  // unset world: default
  for (int i = 0; i < 2; ++i) {
    env.reset(static_cast<std::uint64_t>(11 + i));
    EXPECT_EQ(out.states(i).index(), i == 0 ? 2 : 0);
    EXPECT_EQ(out.states(i).episode_goal().x_m(), env.episode_goal().x());
    for (int k = 0; k < pnp::sim::kObservationSize; ++k)
      EXPECT_EQ(out.states(i).observation().values(k), env.observation()(k));
  }
}

TEST_F(SimServiceTest, RefusesEpisodeSeedsThatDoNotMatchTheEnvironments) {
  const std::string id = create(2);
  grpc::ClientContext c;
  sv1::ResetRequest r;
  sv1::ResetResponse out;
  r.set_env_id(id);
  r.add_episode_seeds(1);  // two environments reset, one seed
  const grpc::Status status = stub_->Reset(&c, r, &out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("episode_seeds"), std::string::npos)
      << status.error_message();
}

TEST_F(SimServiceTest, AScriptedEpisodeThroughTheServiceSucceeds) {
  const std::string id = create(1, 3);
  auto state = reset(id).states(0);
  sv1::StepResult last;
  // Retract only would fail; the scripted pipeline's three phases by predicate:
  pnp::sim::Subtask subtask = pnp::sim::Subtask::kApproach;
  for (int t = 0; t < 50; ++t) {
    pnp::sim::Observation o;
    for (int k = 0; k < 25; ++k) o(k) = state.observation().values(k);
    const Eigen::Vector3d goal(state.episode_goal().x_m(), state.episode_goal().y_m(),
                               state.episode_goal().z_m());
    const auto s = pnp::sim::TaskState::from(o, goal, 0.05);
    if (subtask != pnp::sim::Subtask::kRetract &&
        pnp::sim::objective_done(pnp::sim::objective_of(subtask), s))
      subtask = pnp::sim::kAllSubtasks[static_cast<std::size_t>(subtask) + 1];
    const pnp::sim::Action a = pnp::sim::scripted_action(subtask, s);
    sv1::StepRequest r;
    r.set_env_id(id);
    auto* act = r.add_actions();
    act->set_index(0);
    act->mutable_action()->set_dx(a(0));
    act->mutable_action()->set_dy(a(1));
    act->mutable_action()->set_dz(a(2));
    act->mutable_action()->set_gripper(a(3));
    *act->mutable_goal() = state.episode_goal();
    act->set_objective(sv1::OBJECTIVE_TASK);
    sv1::StepResponse out;
    ASSERT_TRUE(step(r, out).ok());
    last = out.results(0);
    state = last.state();
  }
  EXPECT_TRUE(last.task_success());
  EXPECT_TRUE(last.episode_over());
  // A 51st step is refused, naming the environment.
  sv1::StepRequest more;
  more.set_env_id(id);
  add_action(more, 0, 0.1, {1.3, 0.7, 0.45});
  sv1::StepResponse out;
  const auto status = step(more, out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("Reset"), std::string::npos) << status.error_message();
}

TEST_F(SimServiceTest, ABadActionRefusesTheWholeBatchAndMovesNothing) {
  const std::string id = create(2);
  const auto before = reset(id);
  sv1::StepRequest r;
  r.set_env_id(id);
  add_action(r, 0, 1.0, {1.3, 0.7, 0.45});
  add_action(r, 1, std::nan(""), {1.3, 0.7, 0.45});
  sv1::StepResponse out;
  auto status = step(r, out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("actions[1].action"), std::string::npos)
      << status.error_message();
  // Environment 0 did not move: its first valid step starts from the reset state.
  sv1::StepRequest ok;
  ok.set_env_id(id);
  add_action(ok, 0, 0.0, {1.3, 0.7, 0.45});
  ASSERT_TRUE(step(ok, out).ok());
  EXPECT_EQ(out.results(0).state().elapsed_steps(), 1);

  sv1::StepRequest dup;
  dup.set_env_id(id);
  add_action(dup, 1, 0, {1.3, 0.7, 0.45});
  add_action(dup, 1, 0, {1.3, 0.7, 0.45});
  EXPECT_EQ(step(dup, out).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  sv1::StepRequest range;
  range.set_env_id(id);
  add_action(range, 7, 0, {1.3, 0.7, 0.45});
  EXPECT_EQ(step(range, out).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  sv1::StepRequest unknown;
  unknown.set_env_id("env-999");
  EXPECT_EQ(step(unknown, out).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(SimServiceTest, CreateRefusesBadWorldsAndCountsAndCloseForgets) {
  grpc::ClientContext c1;
  sv1::CreateEnvRequest r;
  sv1::CreateEnvResponse out;
  r.set_robot(common::v1::ROBOT_UNSPECIFIED);
  r.set_object(common::v1::OBJECT_SHAPE_BLOCK);
  r.set_count(1);
  auto status = stub_->CreateEnv(&c1, r, &out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("robot"), std::string::npos);
  grpc::ClientContext c2;
  r.set_robot(common::v1::ROBOT_PANDA);
  r.set_count(65);
  EXPECT_EQ(stub_->CreateEnv(&c2, r, &out).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  grpc::ClientContext c2w;
  r.set_count(1);
  r.set_world(static_cast<common::v1::World>(7));
  status = stub_->CreateEnv(&c2w, r, &out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("world"), std::string::npos) << status.error_message();
  // Found by fuzzing: a huge idle timeout used to overflow its conversion to nanoseconds.
  grpc::ClientContext c2t;
  r.set_world(common::v1::WORLD_UNSPECIFIED);
  r.mutable_idle_timeout()->set_seconds(std::numeric_limits<std::int64_t>::max());
  status = stub_->CreateEnv(&c2t, r, &out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "idle_timeout: expected a duration from 0 to 3600 s (nanos in [0, 1e9)), got "
            "9223372036854775807 s 0 ns");
  r.clear_idle_timeout();
  EXPECT_EQ(service_.registry().environments(), 0);
  const std::string id = create(1);
  grpc::ClientContext c3;
  sv1::CloseEnvRequest close;
  sv1::CloseEnvResponse closed;
  close.set_env_id(id);
  EXPECT_TRUE(stub_->CloseEnv(&c3, close, &closed).ok());
  grpc::ClientContext c4;
  EXPECT_EQ(stub_->CloseEnv(&c4, close, &closed).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(service_.registry().environments(), 0);
}

TEST_F(SimServiceTest, IdleBatchesExpire) {
  const std::string id = create(1);
  EXPECT_EQ(service_.registry().expire(std::chrono::steady_clock::now()), 0);
  EXPECT_EQ(service_.registry().expire(std::chrono::steady_clock::now() + std::chrono::hours(1)),
            1);
  EXPECT_THROW(service_.registry().get(id), Error);
}

TEST_F(SimServiceTest, ComputeRewardAndSpec) {
  grpc::ClientContext c;
  sv1::ComputeRewardRequest r;
  sv1::ComputeRewardResponse out;
  auto* a = r.add_achieved();
  a->set_x_m(1.0);
  auto* g = r.add_goals();
  g->set_x_m(1.3);
  g->set_y_m(0.4);
  ASSERT_TRUE(stub_->ComputeReward(&c, r, &out).ok());
  EXPECT_NEAR(out.rewards(0), -0.5, 1e-12);
  r.add_goals();
  grpc::ClientContext c2;
  EXPECT_EQ(stub_->ComputeReward(&c2, r, &out).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  grpc::ClientContext c3;
  sv1::GetEnvSpecRequest spec_request;
  sv1::GetEnvSpecResponse spec;
  spec_request.set_robot(common::v1::ROBOT_FETCH);
  spec_request.set_object(common::v1::OBJECT_SHAPE_CYLINDER);
  ASSERT_TRUE(stub_->GetEnvSpec(&c3, spec_request, &spec).ok());
  EXPECT_EQ(spec.observation().size(), 25);
  EXPECT_EQ(spec.action().high(0), 1.0);
  EXPECT_EQ(spec.episode_steps(), 50);
  EXPECT_DOUBLE_EQ(spec.step_s(), 0.04);

  // The arm's episode is the arm's; an arm-actuated Fetch is refused naming the field.
  spec_request.set_actuation(common::v1::ACTUATION_ARM);
  grpc::ClientContext c4;
  const grpc::Status fetch_arm = stub_->GetEnvSpec(&c4, spec_request, &spec);
  EXPECT_EQ(fetch_arm.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(fetch_arm.error_message().find("actuation"), std::string::npos);
  spec_request.set_robot(common::v1::ROBOT_PANDA);
  grpc::ClientContext c5;
  ASSERT_TRUE(stub_->GetEnvSpec(&c5, spec_request, &spec).ok());
  EXPECT_EQ(spec.episode_steps(), sim::layout::kArmEpisodeSteps);
}

TEST_F(SimServiceTest, RolloutStreamAnswersEachRequestInOrder) {
  const std::string id = create(1);
  grpc::ClientContext c;
  auto stream = stub_->StreamRollout(&c);
  sv1::StreamRolloutRequest r;
  r.set_env_id(id);
  ASSERT_TRUE(stream->Write(r));
  r.mutable_reset()->set_env_id(id);
  ASSERT_TRUE(stream->Write(r));
  sv1::StreamRolloutResponse out;
  ASSERT_TRUE(stream->Read(&out));
  ASSERT_TRUE(out.has_reset());
  for (int t = 1; t <= 3; ++t) {
    sv1::StreamRolloutRequest s;
    s.mutable_step()->set_env_id(id);
    add_action(*s.mutable_step(), 0, 0.5, {1.3, 0.7, 0.45});
    ASSERT_TRUE(stream->Write(s));
    ASSERT_TRUE(stream->Read(&out));
    EXPECT_EQ(out.step().results(0).state().elapsed_steps(), t);
  }
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

}  // namespace
}  // namespace pnp::services
