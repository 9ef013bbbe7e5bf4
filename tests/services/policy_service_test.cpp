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
#include "services/common/convert.h"
#include "services/common/server_runtime.h"
#include "serving/served_end_to_end.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_expert.h"
#include "sim/subtask.h"
#include "sim/world_layout.h"
#include "store/run_store.h"

namespace pnp::services {
namespace {

namespace pv1 = policy::v1;

std::vector<std::uint8_t> expert_blob(const std::string& role, std::uint64_t seed) {
  rl::DdpgHerConfig config;
  config.hidden = {16};
  Rng rng(seed);
  rl::DdpgHerAgent agent(config, rng);
  const rl::ExpertMeta meta{role,
                            "ddpg_her",
                            "fetch",
                            "block",
                            "paper",
                            config.hidden,
                            config.hidden_activation,
                            true,
                            200,
                            5,
                            0.01,
                            0,
                            0,
                            seed,
                            "test"};
  return rl::save_expert(meta, agent.actor(), nullptr, agent.observation_normalizer(),
                         agent.goal_normalizer());
}

// An end-to-end DDPG+HER checkpoint with random weights and normalisers fitted to a few
// real episode states (so that normalisation matters to the action).
std::vector<std::uint8_t> e2e_blob(std::uint64_t seed, bool learn_gripper = true) {
  rl::DdpgHerConfig config;
  config.hidden = {16};
  Rng rng(seed);
  rl::DdpgHerAgent agent(config, rng);
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
  std::vector<sim::Observation> observations;
  std::vector<sim::Goal> goals;
  for (std::uint64_t episode = 0; episode < 4; ++episode) {
    env.reset(seed * 100 + episode);
    observations.push_back(env.observation());
    goals.push_back(env.episode_goal());
  }
  agent.update_normalizers(observations, goals);
  rl::ExpertMeta meta;
  meta.role = "e2e";
  meta.algorithm = "ddpg_her";
  meta.robot = "fetch";
  meta.object = "block";
  meta.world = "gym";  // not the default, so that the status shows it is carried
  meta.hidden = config.hidden;
  meta.learn_gripper = learn_gripper;
  meta.seed = seed;
  meta.code_commit = "test";
  return rl::save_expert(meta, agent.actor(), nullptr, agent.observation_normalizer(),
                         agent.goal_normalizer());
}

// The action the e2e checkpoint's actor computes directly, unbatched and unserved.
sim::Action direct_e2e_action(const std::vector<std::uint8_t>& blob,
                              const sim::Observation& observation, const sim::Goal& goal) {
  const rl::LoadedExpert e = rl::load_expert(blob);
  rl::ActorSnapshot actor(e.actor, e.observation_normalizer, e.goal_normalizer, e.meta.clip_obs);
  return actor.act(observation, goal);
}

sim::Action action_of(const pv1::PredictResponse& r) {
  return sim::Action(r.action().dx(), r.action().dy(), r.action().dz(), r.action().gripper());
}

std::vector<std::uint8_t> choreographer_blob(std::uint64_t seed) {
  rl::ChoreographerNet net({{16}, 4});
  Rng rng(seed);
  net.initialise(rng);
  return rl::save_choreographer({"fetch", "block", "paper", net.spec(), 0, 0, seed, "test"}, net);
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

  void start(serving::PolicyKind kind = serving::PolicyKind::kHierarchy,
             MetricsRegistry* metrics = nullptr) {
    service_ = std::make_unique<PolicyServiceImpl>(db_, kind, nullptr, metrics);
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

  static sim::Observation observation_of(const pv1::PredictRequest& r) {
    return from_proto(r.observation(), "observation");
  }
  static sim::Goal goal_of(const pv1::PredictRequest& r) { return from_proto(r.goal(), "goal"); }

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

// A checkpoint no replica could serve (its weights are not numbers, or it is another
// role's file) is refused before the promotion commits, naming it; the hierarchy served
// before keeps serving.
TEST_F(PolicyServiceTest, ACheckpointThatFailsItsProbeIsNeverPromoted) {
  promote_all(1);
  start();
  rl::ChoreographerNet net({{16}, 4});
  Rng rng(5);
  net.initialise(rng);
  net.parameter_blocks()[0][0] = std::nanf("");
  const auto poisoned = store_checkpoint(
      "hlc", rl::save_choreographer({"fetch", "block", "paper", net.spec(), 0, 0, 5, "test"}, net));
  const auto misfiled = store_checkpoint("hlc", expert_blob("retract", 5));
  for (const auto id : {poisoned, misfiled}) {
    grpc::ClientContext context;
    pv1::PromoteCheckpointRequest promote;
    pv1::PromoteCheckpointResponse promoted;
    promote.add_checkpoint_ids(ids_[0]);
    promote.add_checkpoint_ids(id);
    const grpc::Status status = stub_->PromoteCheckpoint(&context, promote, &promoted);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(status.error_message().rfind("checkpoint_ids[1] " + std::to_string(id) + ": ", 0), 0u)
        << status.error_message();
  }
  EXPECT_EQ(store_->promoted("hlc")->checkpoint_id, ids_[3]) << "nothing was promoted";
  grpc::ClientContext context;
  pv1::PredictResponse response;
  ASSERT_TRUE(stub_->Predict(&context, valid_request(), &response).ok());
  EXPECT_EQ(response.choreographer_checkpoint_id(), ids_[3]);
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
  EXPECT_EQ(out.env_steps(), 100);
  EXPECT_GT(out.run_id(), 0);
  EXPECT_TRUE(out.latest_of_run());
  // An earlier checkpoint of a run is promoted as asked, and the answer says it is not the
  // run's latest (a run id typed where a checkpoint id belongs shows up here).
  const auto run = store_->create_run({"hlc", "a3c", "fetch", "block", 1, "{}", "", std::nullopt});
  const auto early = store_->save_checkpoint(run.id, 100, 0.5, choreographer_blob(3));
  store_->save_checkpoint(run.id, 200, 0.9, choreographer_blob(3));
  grpc::ClientContext c2;
  r.set_checkpoint_id(early.id);
  ASSERT_TRUE(stub_->PromoteCheckpoint(&c2, r, &out).ok());
  EXPECT_EQ(out.run_id(), run.id);
  EXPECT_FALSE(out.latest_of_run());
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

// A session declares its episode's length in its first request and the hierarchy's subtask
// caps scale to it; 0 is the served policy's own (this mocap-trained one's 50 steps).
// A length out of bounds, or changed mid-session, is refused naming episode_steps.
TEST_F(PolicyServiceTest, ASessionsDeclaredEpisodeSetsTheSubtaskCaps) {
  promote_all(1);
  start();
  const auto r = valid_request();  // the same state every step: no subtask finishes
  // Answers until the choreographer decides a second time, and its first subtask.
  const auto first_span = [&](int declared) {
    grpc::ClientContext context;
    auto session = stub_->PredictSession(&context);
    pv1::PredictSessionRequest step;
    *step.mutable_observation() = r.observation();
    *step.mutable_goal() = r.goal();
    step.set_episode_steps(declared);
    pv1::PredictSessionResponse answer;
    EXPECT_TRUE(session->Write(step) && session->Read(&answer));
    const auto first = answer.prediction().subtask();
    int steps = 1;
    while (steps < 1000 && session->Write(step) && session->Read(&answer) && !answer.decided())
      ++steps;
    session->WritesDone();
    EXPECT_TRUE(session->Finish().ok());
    return std::pair{first, steps};
  };
  const auto [first, own] = first_span(0);
  const auto [first_on_arm, on_arm] = first_span(sim::layout::kArmEpisodeSteps);
  EXPECT_EQ(first_on_arm, first);
  sim::Subtask subtask = sim::Subtask::kApproach;
  for (sim::Subtask s : sim::kAllSubtasks)
    if (to_proto(s) == first) subtask = s;
  EXPECT_EQ(own, sim::step_cap(subtask, sim::layout::kEpisodeSteps));
  EXPECT_EQ(on_arm, sim::step_cap(subtask, sim::layout::kArmEpisodeSteps));

  for (const auto& [first_steps, later_steps] : std::initializer_list<std::pair<int, int>>{
           {-1, 0}, {sim::layout::kMaxEpisodeSteps + 1, 0}, {75, 50}}) {
    grpc::ClientContext context;
    auto session = stub_->PredictSession(&context);
    pv1::PredictSessionRequest step;
    *step.mutable_observation() = r.observation();
    *step.mutable_goal() = r.goal();
    step.set_episode_steps(first_steps);
    pv1::PredictSessionResponse answer;
    if (session->Write(step) && session->Read(&answer)) {
      step.set_episode_steps(later_steps);
      session->Write(step);
      session->Read(&answer);
    }
    session->WritesDone();
    const grpc::Status status = session->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << first_steps;
    EXPECT_NE(status.error_message().find("episode_steps"), std::string::npos)
        << status.error_message();
  }
}

// Each session answer's time in the server is observed once (the session's RPC duration is
// the whole episode's, which says nothing about a step's latency).
TEST_F(PolicyServiceTest, EverySessionAnswerIsTimedInTheServer) {
  promote_all(1);
  MetricsRegistry metrics;
  start(serving::PolicyKind::kHierarchy, &metrics);
  grpc::ClientContext session_context;
  auto session = stub_->PredictSession(&session_context);
  const auto r = valid_request();
  pv1::PredictSessionRequest step;
  *step.mutable_observation() = r.observation();
  *step.mutable_goal() = r.goal();
  pv1::PredictSessionResponse answer;
  for (int t = 0; t < 3; ++t) {
    ASSERT_TRUE(session->Write(step));
    ASSERT_TRUE(session->Read(&answer));
  }
  session->WritesDone();
  ASSERT_TRUE(session->Finish().ok());
  const std::string text = metrics.render();
  EXPECT_NE(text.find("\npnp_inference_session_step_seconds_count 3\n"), std::string::npos) << text;
  EXPECT_NE(text.find("pnp_inference_session_step_seconds_bucket{le=\"0.002\"}"),
            std::string::npos);
}

// A hierarchy promoted in one call is served whole; two checkpoints of one role are
// refused naming the field, and nothing changes.
TEST_F(PolicyServiceTest, PromotesAWholeHierarchyInOneCall) {
  promote_all(1);
  start();
  std::vector<std::int64_t> next;
  for (const char* role : {"approach", "manipulate", "retract"})
    next.push_back(store_checkpoint(role, expert_blob(role, 2)));
  next.push_back(store_checkpoint("hlc", choreographer_blob(2)));
  pv1::PromoteCheckpointRequest request;
  for (const auto id : next) request.add_checkpoint_ids(id);
  request.add_checkpoint_ids(next[0]);  // approach twice
  pv1::PromoteCheckpointResponse response;
  {
    grpc::ClientContext context;
    const auto status = stub_->PromoteCheckpoint(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find("checkpoint_ids"), std::string::npos);
  }
  EXPECT_EQ(store_->promoted("approach")->checkpoint_id, ids_[0]) << "a refusal changes nothing";
  request.mutable_checkpoint_ids()->RemoveLast();
  grpc::ClientContext context;
  ASSERT_TRUE(stub_->PromoteCheckpoint(&context, request, &response).ok());
  ASSERT_EQ(response.promoted_size(), 4);
  EXPECT_EQ(response.checkpoint_id(), next[0]);
  EXPECT_EQ(response.promoted(3).checkpoint_id(), next[3]);
  grpc::ClientContext predict_context;
  pv1::PredictResponse predicted;
  ASSERT_TRUE(stub_->Predict(&predict_context, valid_request(), &predicted).ok());
  EXPECT_EQ(predicted.choreographer_checkpoint_id(), next[3]) << "the new hierarchy is served";
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

// ---- --policy e2e: the end-to-end DDPG+HER baseline ----

TEST_F(PolicyServiceTest, E2ePredictAnswersWithTheE2eActorOnTheEpisodeGoal) {
  promote_all(1);  // a promoted hierarchy is not what e2e serves
  const auto blob = e2e_blob(5);
  const auto e2e = store_->promote(store_checkpoint("e2e", blob)).checkpoint_id;
  start(serving::PolicyKind::kEndToEnd);
  EXPECT_TRUE(service_->ready());
  EXPECT_EQ(service_->kind(), serving::PolicyKind::kEndToEnd);
  for (const std::uint64_t seed : {3u, 4u, 5u}) {
    sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
    env.reset(seed);
    const auto request = request_from(env);
    grpc::ClientContext context;
    pv1::PredictResponse response;
    const auto status = stub_->Predict(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    const sim::Action expected = direct_e2e_action(blob, env.observation(), env.episode_goal());
    EXPECT_LE((action_of(response) - expected).cwiseAbs().maxCoeff(), 1e-6)
        << "served " << action_of(response).transpose() << " direct " << expected.transpose();
    EXPECT_EQ(response.subtask(), common::v1::SUBTASK_UNSPECIFIED);
    EXPECT_EQ(response.subtask_probabilities_size(), 0);
    EXPECT_EQ(response.value(), 0.0);
    EXPECT_EQ(response.expert_checkpoint_id(), e2e);
    EXPECT_EQ(response.choreographer_checkpoint_id(), 0);
  }
  const auto stats = service_->batch_stats();
  ASSERT_EQ(stats.size(), 1u) << "one batched actor: e2e";
  EXPECT_EQ(stats[0].requests, 3u);
}

TEST_F(PolicyServiceTest, E2eSessionAnswersEveryStepWithTheE2eActor) {
  const auto blob = e2e_blob(6);
  const auto e2e = store_->promote(store_checkpoint("e2e", blob)).checkpoint_id;
  start(serving::PolicyKind::kEndToEnd);
  sim::PickPlaceEnv env(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock));
  env.reset(21);
  grpc::ClientContext session_context;
  auto session = stub_->PredictSession(&session_context);
  pv1::PredictSessionRequest step;
  pv1::PredictSessionResponse answer;
  for (int t = 1; t <= 8; ++t) {
    const auto r = request_from(env);
    *step.mutable_observation() = r.observation();
    *step.mutable_goal() = r.goal();
    ASSERT_TRUE(session->Write(step));
    ASSERT_TRUE(session->Read(&answer));
    const sim::Action served = action_of(answer.prediction());
    const sim::Action expected = direct_e2e_action(blob, env.observation(), env.episode_goal());
    EXPECT_LE((served - expected).cwiseAbs().maxCoeff(), 1e-6) << "step " << t;
    EXPECT_EQ(answer.prediction().subtask(), common::v1::SUBTASK_UNSPECIFIED);
    EXPECT_EQ(answer.prediction().subtask_probabilities_size(), 0);
    EXPECT_EQ(answer.prediction().expert_checkpoint_id(), e2e);
    EXPECT_EQ(answer.prediction().choreographer_checkpoint_id(), 0);
    EXPECT_FALSE(answer.decided()) << "no choreographer decides";
    EXPECT_FALSE(answer.placed()) << "the e2e actor acts at every step";
    EXPECT_EQ(answer.step(), t);
    env.step(served, env.episode_goal(), sim::Objective::kTask);
  }
  session->WritesDone();
  EXPECT_TRUE(session->Finish().ok());
}

TEST_F(PolicyServiceTest, E2eWithoutALearnedGripperClosesItAsScriptedRetract) {
  const auto blob = e2e_blob(7, /*learn_gripper=*/false);
  store_->promote(store_checkpoint("e2e", blob));
  start(serving::PolicyKind::kEndToEnd);
  const auto request = valid_request();
  grpc::ClientContext context;
  pv1::PredictResponse response;
  ASSERT_TRUE(stub_->Predict(&context, request, &response).ok());
  const sim::Observation o = observation_of(request);
  const sim::Goal g = goal_of(request);
  const sim::Action arm = direct_e2e_action(blob, o, g);
  const double width =
      2 * sim::object_spec(sim::ObjectShape::kBlock).half_width_m;  // the served object's
  const double gripper =
      sim::scripted_action(sim::Subtask::kRetract, sim::TaskState::from(o, g, width))(3);
  EXPECT_LE((action_of(response).head<3>() - arm.head<3>()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(response.action().gripper(), gripper);
}

TEST_F(PolicyServiceTest, E2eWithNothingPromotedIsAFailedPreconditionNamingE2e) {
  promote_all(1);  // the hierarchy does not stand in for e2e
  start(serving::PolicyKind::kEndToEnd);
  EXPECT_FALSE(service_->ready());
  ASSERT_EQ(service_->batch_stats().size(), 1u);
  EXPECT_EQ(service_->batch_stats()[0].requests, 0u);
  grpc::ClientContext context;
  pv1::PredictResponse response;
  auto status = stub_->Predict(&context, valid_request(), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("e2e"), std::string::npos) << status.error_message();
  {
    grpc::ClientContext session_context;
    auto session = stub_->PredictSession(&session_context);
    pv1::PredictSessionRequest step;
    const auto r = valid_request();
    *step.mutable_observation() = r.observation();
    *step.mutable_goal() = r.goal();
    session->Write(step);
    session->WritesDone();
    pv1::PredictSessionResponse answer;
    EXPECT_FALSE(session->Read(&answer));
    status = session->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_NE(status.error_message().find("e2e"), std::string::npos) << status.error_message();
  }
  EXPECT_THROW(service_->reload(), pnp::Error);
  try {
    service_->reload();
  } catch (const pnp::Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("e2e"), std::string::npos) << e.what();
  }
  grpc::ClientContext status_context;
  pv1::GetServingStatusResponse serving;
  ASSERT_TRUE(stub_->GetServingStatus(&status_context, {}, &serving).ok());
  EXPECT_FALSE(serving.ready());
  EXPECT_EQ(serving.roles_size(), 0) << "the hierarchy's roles serve nothing in e2e mode";
}

TEST_F(PolicyServiceTest, E2ePromotionThroughTheServiceServesAndReloads) {
  start(serving::PolicyKind::kEndToEnd);
  auto promote = [&](std::int64_t id) {
    grpc::ClientContext c;
    pv1::PromoteCheckpointRequest r;
    pv1::PromoteCheckpointResponse out;
    r.set_checkpoint_id(id);
    const auto status = stub_->PromoteCheckpoint(&c, r, &out);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return out;
  };
  const auto first_blob = e2e_blob(8);
  const auto first = store_checkpoint("e2e", first_blob);
  const auto promoted = promote(first);
  EXPECT_EQ(promoted.role(), common::v1::ROLE_E2E);
  EXPECT_EQ(promoted.checkpoint_id(), first);
  EXPECT_TRUE(service_->ready());

  // Hierarchy roles promoted meanwhile change nothing here.
  promote(store_checkpoint("approach", expert_blob("approach", 3)));
  EXPECT_FALSE(service_->reload());

  grpc::ClientContext status_context;
  pv1::GetServingStatusResponse serving;
  ASSERT_TRUE(stub_->GetServingStatus(&status_context, {}, &serving).ok());
  EXPECT_TRUE(serving.ready());
  ASSERT_EQ(serving.roles_size(), 1);
  EXPECT_EQ(serving.roles(0).role(), common::v1::ROLE_E2E);
  EXPECT_EQ(serving.roles(0).checkpoint_id(), first);
  EXPECT_EQ(serving.roles(0).robot(), common::v1::ROBOT_FETCH);
  EXPECT_EQ(serving.roles(0).object(), common::v1::OBJECT_SHAPE_BLOCK);
  EXPECT_EQ(serving.roles(0).world(), common::v1::WORLD_GYM);

  // A session open on the first keeps it; a new e2e promotion serves new requests.
  grpc::ClientContext session_context;
  auto session = stub_->PredictSession(&session_context);
  pv1::PredictSessionRequest step;
  pv1::PredictSessionResponse answer;
  const auto r = valid_request();
  *step.mutable_observation() = r.observation();
  *step.mutable_goal() = r.goal();
  ASSERT_TRUE(session->Write(step));
  ASSERT_TRUE(session->Read(&answer));
  EXPECT_EQ(answer.prediction().expert_checkpoint_id(), first);

  const auto second_blob = e2e_blob(9);
  const auto second = store_checkpoint("e2e", second_blob);
  promote(second);
  ASSERT_TRUE(session->Write(step));
  ASSERT_TRUE(session->Read(&answer));
  EXPECT_EQ(answer.prediction().expert_checkpoint_id(), first);
  EXPECT_LE((action_of(answer.prediction()) -
             direct_e2e_action(first_blob, observation_of(r), goal_of(r)))
                .cwiseAbs()
                .maxCoeff(),
            1e-6);
  session->WritesDone();
  EXPECT_TRUE(session->Finish().ok());

  grpc::ClientContext context;
  pv1::PredictResponse response;
  ASSERT_TRUE(stub_->Predict(&context, r, &response).ok());
  EXPECT_EQ(response.expert_checkpoint_id(), second);
  EXPECT_LE((action_of(response) - direct_e2e_action(second_blob, observation_of(r), goal_of(r)))
                .cwiseAbs()
                .maxCoeff(),
            1e-6);
}

TEST_F(PolicyServiceTest, HierarchyModeIgnoresAPromotedE2eCheckpoint) {
  promote_all(1);
  const auto e2e = store_->promote(store_checkpoint("e2e", e2e_blob(5))).checkpoint_id;
  start();
  EXPECT_EQ(service_->kind(), serving::PolicyKind::kHierarchy);
  grpc::ClientContext context;
  pv1::PredictResponse response;
  ASSERT_TRUE(stub_->Predict(&context, valid_request(), &response).ok());
  EXPECT_NE(response.subtask(), common::v1::SUBTASK_UNSPECIFIED);
  EXPECT_NE(response.expert_checkpoint_id(), e2e);
  EXPECT_EQ(response.choreographer_checkpoint_id(), ids_[3]);
  EXPECT_EQ(service_->batch_stats().size(), 3u);
  grpc::ClientContext status_context;
  pv1::GetServingStatusResponse serving;
  ASSERT_TRUE(stub_->GetServingStatus(&status_context, {}, &serving).ok());
  EXPECT_TRUE(serving.ready());
  EXPECT_EQ(serving.roles_size(), 4);
  for (const auto& role : serving.roles()) {
    EXPECT_NE(role.role(), common::v1::ROLE_E2E);
    EXPECT_EQ(role.world(), common::v1::WORLD_PAPER) << "the choreographer's world";
  }
}

TEST(ServedEndToEnd, RefusesACheckpointOfAnotherRoleNamingIt) {
  rl::LoadedExpert approach = rl::load_expert(expert_blob("approach", 1));
  try {
    serving::ServedEndToEnd served(std::move(approach), 42);
    FAIL() << "an approach checkpoint was served as e2e";
  } catch (const pnp::Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("e2e checkpoint 42"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("role approach"), std::string::npos) << e.what();
  }
  EXPECT_EQ(serving::parse_policy_kind("e2e"), serving::PolicyKind::kEndToEnd);
  EXPECT_EQ(serving::parse_policy_kind("hierarchy"), serving::PolicyKind::kHierarchy);
  EXPECT_THROW(serving::parse_policy_kind("hlc"), pnp::Error);
}

}  // namespace
}  // namespace pnp::services
