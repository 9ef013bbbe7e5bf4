// In-process gRPC tests of PolicyService: a real server on a free loopback port, called
// through a real stub, over a real store.
#include "services/inference/policy_service.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "common/error.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "services/common/server_runtime.h"
#include "sim/pick_place_env.h"

namespace pnp::services {
namespace {

namespace pv1 = policy::v1;

std::vector<std::uint8_t> expert_blob(const std::string& role, std::uint64_t seed) {
  rl::DdpgHerConfig config;
  config.hidden = {16};
  Rng rng(seed);
  rl::DdpgHerAgent agent(config, rng);
  const rl::ExpertMeta meta{role, "ddpg_her", "fetch", "block", config.hidden, true,  200,
                            5,    0.01,       0,       0,       seed,          "test"};
  return rl::save_expert(meta, agent.actor(), nullptr, agent.observation_normalizer(),
                         agent.goal_normalizer());
}

std::vector<std::uint8_t> choreographer_blob(std::uint64_t seed) {
  rl::ChoreographerNet net({{16}, 4});
  Rng rng(seed);
  net.initialise(rng);
  return rl::save_choreographer({"fetch", "block", net.spec(), 0, 0, seed, "test"}, net);
}

class PolicyServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("pnp_policy_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    db_ = (dir_ / "pnp.db").string();
    store_ = std::make_unique<store::RunStore>(db_);
  }
  void TearDown() override {
    if (runtime_) runtime_->shutdown(std::chrono::milliseconds(500));
    std::filesystem::remove_all(dir_);
  }

  std::int64_t store_checkpoint(const std::string& role, std::vector<std::uint8_t> blob) {
    store::RunSpec spec{
        role, role == "hlc" ? "a3c" : "ddpg_her", "fetch", "block", 1, "{}", "", std::nullopt};
    const auto run = store_->create_run(spec);
    return store_->save_checkpoint(run.id, 100, 0.9, blob).id;
  }

  void promote_all(std::uint64_t seed) {
    for (const char* role : {"approach", "manipulate", "retract"})
      ids_.push_back(
          store_->promote(store_checkpoint(role, expert_blob(role, seed))).checkpoint_id);
    ids_.push_back(
        store_->promote(store_checkpoint("hlc", choreographer_blob(seed))).checkpoint_id);
  }

  void start() {
    service_ = std::make_unique<PolicyServiceImpl>(db_);
    runtime_ = std::make_unique<ServerRuntime>(
        ServerConfig{"127.0.0.1:0", 1 << 20, {service_.get()}, {"pnp.policy.v1.PolicyService"}});
    stub_ = pv1::PolicyService::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string(runtime_->port()), grpc::InsecureChannelCredentials()));
  }

  static pv1::PredictRequest request_from(const sim::PickPlaceEnv& env) {
    pv1::PredictRequest r;
    for (int k = 0; k < sim::kObservationSize; ++k)
      r.mutable_observation()->add_values(env.observation()(k));
    r.mutable_goal()->set_x_m(env.episode_goal().x());
    r.mutable_goal()->set_y_m(env.episode_goal().y());
    r.mutable_goal()->set_z_m(env.episode_goal().z());
    return r;
  }

  pv1::PredictRequest valid_request() {
    sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
    env.reset(3);
    return request_from(env);
  }

  std::filesystem::path dir_;
  std::string db_;
  std::unique_ptr<store::RunStore> store_;
  std::vector<std::int64_t> ids_;
  std::unique_ptr<PolicyServiceImpl> service_;
  std::unique_ptr<ServerRuntime> runtime_;
  std::unique_ptr<pv1::PolicyService::Stub> stub_;
};

TEST_F(PolicyServiceTest, PredictAnswersWithThePromotedHierarchy) {
  promote_all(1);
  start();
  grpc::ClientContext context;
  pv1::PredictResponse response;
  const auto status = stub_->Predict(&context, valid_request(), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_NE(response.subtask(), common::v1::SUBTASK_UNSPECIFIED);
  ASSERT_EQ(response.subtask_probabilities_size(), 3);
  double sum = 0;
  for (double p : response.subtask_probabilities()) sum += p;
  EXPECT_NEAR(sum, 1.0, 1e-9);
  EXPECT_EQ(response.choreographer_checkpoint_id(), ids_[3]);
  EXPECT_LE(std::abs(response.action().dx()), 1.0);
  grpc::ClientContext ping_context;
  pv1::PingResponse pong;
  EXPECT_TRUE(stub_->Ping(&ping_context, {}, &pong).ok());
}

TEST_F(PolicyServiceTest, BadInputIsRefusedNamingTheField) {
  promote_all(1);
  start();
  auto call = [&](const pv1::PredictRequest& r) {
    grpc::ClientContext context;
    pv1::PredictResponse response;
    return stub_->Predict(&context, r, &response);
  };
  pv1::PredictRequest short_obs = valid_request();
  short_obs.mutable_observation()->mutable_values()->RemoveLast();
  auto status = call(short_obs);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "observation.values: expected 25 values, got 24");
  pv1::PredictRequest nan = valid_request();
  nan.mutable_observation()->set_values(7, std::nan(""));
  status = call(nan);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("observation.values[7]"), std::string::npos);
  pv1::PredictRequest bad_goal = valid_request();
  bad_goal.mutable_goal()->set_z_m(INFINITY);
  EXPECT_EQ(call(bad_goal).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  grpc::ClientContext context;
  pv1::PromoteCheckpointRequest promote;
  pv1::PromoteCheckpointResponse promoted;
  promote.set_checkpoint_id(9999);
  EXPECT_EQ(stub_->PromoteCheckpoint(&context, promote, &promoted).error_code(),
            grpc::StatusCode::NOT_FOUND);
  grpc::ClientContext context2;
  promote.set_checkpoint_id(0);
  EXPECT_EQ(stub_->PromoteCheckpoint(&context2, promote, &promoted).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(store_->promoted("hlc")->checkpoint_id, ids_[3]) << "refusals change nothing";
}

TEST_F(PolicyServiceTest, NothingPromotedIsAFailedPreconditionThenServesOncePromoted) {
  start();
  grpc::ClientContext status_context;
  pv1::GetServingStatusResponse serving;
  ASSERT_TRUE(stub_->GetServingStatus(&status_context, {}, &serving).ok());
  EXPECT_FALSE(serving.ready());
  grpc::ClientContext context;
  pv1::PredictResponse response;
  const auto status = stub_->Predict(&context, valid_request(), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);

  // Promote through the service: the last role completes the hierarchy and it serves.
  for (const char* role : {"approach", "manipulate", "retract"}) {
    grpc::ClientContext c;
    pv1::PromoteCheckpointRequest r;
    pv1::PromoteCheckpointResponse out;
    r.set_checkpoint_id(store_checkpoint(role, expert_blob(role, 2)));
    ASSERT_TRUE(stub_->PromoteCheckpoint(&c, r, &out).ok());
  }
  grpc::ClientContext c;
  pv1::PromoteCheckpointRequest r;
  pv1::PromoteCheckpointResponse out;
  r.set_checkpoint_id(store_checkpoint("hlc", choreographer_blob(2)));
  ASSERT_TRUE(stub_->PromoteCheckpoint(&c, r, &out).ok());
  EXPECT_EQ(out.role(), common::v1::ROLE_HLC);
  grpc::ClientContext again;
  EXPECT_TRUE(stub_->Predict(&again, valid_request(), &response).ok());
}

TEST_F(PolicyServiceTest, ASessionKeepsItsHierarchyWhileANewPromotionServesNewRequests) {
  promote_all(1);
  start();
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
  env.reset(11);
  grpc::ClientContext session_context;
  auto session = stub_->PredictSession(&session_context);
  pv1::PredictSessionRequest step;
  pv1::PredictSessionResponse answer;
  auto send_state = [&] {
    const auto r = request_from(env);
    *step.mutable_observation() = r.observation();
    *step.mutable_goal() = r.goal();
    ASSERT_TRUE(session->Write(step));
    ASSERT_TRUE(session->Read(&answer));
  };
  send_state();
  EXPECT_TRUE(answer.decided()) << "the first step is a decision";
  EXPECT_EQ(answer.step(), 1);

  // A new choreographer is promoted mid-episode.
  const auto new_hlc = store_checkpoint("hlc", choreographer_blob(9));
  grpc::ClientContext promote_context;
  pv1::PromoteCheckpointRequest promote;
  pv1::PromoteCheckpointResponse promoted;
  promote.set_checkpoint_id(new_hlc);
  ASSERT_TRUE(stub_->PromoteCheckpoint(&promote_context, promote, &promoted).ok());

  for (int t = 0; t < 5; ++t) {
    const auto& a = answer.prediction().action();
    env.step(sim::Action(a.dx(), a.dy(), a.dz(), a.gripper()), env.episode_goal(),
             sim::Objective::kTask);
    send_state();
    EXPECT_EQ(answer.prediction().choreographer_checkpoint_id(), ids_[3]);
  }
  EXPECT_EQ(answer.step(), 6);
  session->WritesDone();
  EXPECT_TRUE(session->Finish().ok());

  grpc::ClientContext context;
  pv1::PredictResponse response;
  ASSERT_TRUE(stub_->Predict(&context, valid_request(), &response).ok());
  EXPECT_EQ(response.choreographer_checkpoint_id(), new_hlc);
}

TEST_F(PolicyServiceTest, ACorruptedPromotedCheckpointIsNeverServed) {
  promote_all(1);
  store_->database().execute("UPDATE checkpoints SET blob = x'00' || substr(blob, 2) WHERE id = " +
                             std::to_string(ids_[0]));
  start();
  grpc::ClientContext context;
  pv1::PredictResponse response;
  const auto status = stub_->Predict(&context, valid_request(), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION)
      << "nothing is served rather than a corrupted expert";
  EXPECT_THROW(service_->reload(), pnp::Error);
}

}  // namespace
}  // namespace pnp::services
