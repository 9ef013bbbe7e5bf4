// In-process gRPC tests of TrainingService: a real server on a free loopback port with a
// real RunManager and store, called through a real stub.
#include "services/train/training_service.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "services/common/server_runtime.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/core/training/small_runs.h"

namespace pnp::services {
namespace {

namespace tv1 = train::v1;
using training::testing::ScratchDir;

struct BadCreate {
  const char* name;
  std::function<void(tv1::CreateTrainingRunRequest&)> change;
  grpc::StatusCode code;
  const char* message;
};

class TrainingServiceTest : public ::testing::Test {
 protected:
  void start(const std::string& role) {
    manager_ = std::make_unique<training::RunManager>(
        training::RunManagerOptions{dir_.file("pnp.db"), role, "test", 1});
    service_ = std::make_unique<TrainingServiceImpl>(*manager_);
    runtime_ = std::make_unique<ServerRuntime>(
        ServerConfig{"127.0.0.1:0", 1 << 20, {service_.get()}, {"pnp.train.v1.TrainingService"}});
    stub_ = tv1::TrainingService::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string(runtime_->port()), grpc::InsecureChannelCredentials()));
  }
  void expect_refused(const std::vector<BadCreate>& cases,
                      const tv1::CreateTrainingRunRequest& base);
  void TearDown() override {
    if (runtime_) runtime_->shutdown(std::chrono::milliseconds(500));
  }

  // A small approach run (see small_runs.h), as a client would ask for it.
  static tv1::CreateTrainingRunRequest small_request(long long max_steps = 400) {
    tv1::CreateTrainingRunRequest r;
    r.set_role(common::v1::ROLE_APPROACH);
    r.set_algorithm(tv1::ALGORITHM_DDPG_HER);
    r.set_robot(common::v1::ROBOT_FETCH);
    r.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    r.set_seed(3);
    r.mutable_stop()->set_max_steps(max_steps);
    r.mutable_stop()->set_eval_interval_steps(200);
    r.mutable_stop()->set_eval_episodes(10);
    r.mutable_stop()->set_target_success(1.0);
    auto& d = *r.mutable_ddpg();
    d.add_hidden(32);
    d.add_hidden(32);
    d.set_batch_size(32);
    d.set_buffer_size(20'000);
    d.set_demo_episodes(2);
    d.set_updates_per_transition(0.25);
    return r;
  }

  grpc::Status create(const tv1::CreateTrainingRunRequest& r, tv1::CreateTrainingRunResponse& out) {
    grpc::ClientContext context;
    return stub_->CreateTrainingRun(&context, r, &out);
  }

  // Watches a run to its end; returns every message.
  std::vector<tv1::WatchTrainingRunResponse> watch(std::int64_t id) {
    grpc::ClientContext context;
    tv1::WatchTrainingRunRequest request;
    request.set_run_id(id);
    auto reader = stub_->WatchTrainingRun(&context, request);
    std::vector<tv1::WatchTrainingRunResponse> out;
    for (tv1::WatchTrainingRunResponse m; reader->Read(&m);) out.push_back(m);
    EXPECT_TRUE(reader->Finish().ok());
    return out;
  }

  std::size_t run_count() {
    grpc::ClientContext context;
    tv1::ListTrainingRunsResponse out;
    EXPECT_TRUE(stub_->ListTrainingRuns(&context, {}, &out).ok());
    return static_cast<std::size_t>(out.runs_size());
  }

  ScratchDir dir_{std::string("training_service_") +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name()};
  std::unique_ptr<training::RunManager> manager_;
  std::unique_ptr<TrainingServiceImpl> service_;
  std::unique_ptr<ServerRuntime> runtime_;
  std::unique_ptr<tv1::TrainingService::Stub> stub_;
};

// pnpctl and the Python client send one key per run they mean: a call retried after its
// answer was lost gets the run the first created, not a second training run.
TEST_F(TrainingServiceTest, ARetriedCreationWithItsKeyCreatesOneRun) {
  start("approach");
  auto request = small_request(/*max_steps=*/200);
  request.set_request_id("0123456789abcdef0123456789abcdef");
  tv1::CreateTrainingRunResponse first, retried;
  ASSERT_TRUE(create(request, first).ok());
  ASSERT_TRUE(create(request, retried).ok());
  EXPECT_EQ(retried.run().run_id(), first.run().run_id());
  EXPECT_EQ(run_count(), 1u);
  request.set_request_id(std::string(129, 'k'));
  tv1::CreateTrainingRunResponse refused;
  const grpc::Status status = create(request, refused);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("request_id"), std::string::npos) << status.error_message();
  EXPECT_EQ(run_count(), 1u);
}

TEST_F(TrainingServiceTest, CreateWatchMetricsAndCheckpoints) {
  start("approach");
  tv1::CreateTrainingRunResponse created;
  ASSERT_TRUE(create(small_request(), created).ok());
  const std::int64_t id = created.run().run_id();
  EXPECT_GT(id, 0);
  EXPECT_EQ(created.run().max_steps(), 400);
  const auto messages = watch(id);
  ASSERT_GE(messages.size(), 3u);  // the state now, >= 2 evaluations, the final state
  EXPECT_FALSE(messages.front().has_metric());
  EXPECT_EQ(messages.back().run().state(), tv1::RUN_STATE_SUCCEEDED);
  int evaluations = 0;
  for (const auto& m : messages) evaluations += m.has_metric() ? 1 : 0;
  EXPECT_GE(evaluations, 2);

  grpc::ClientContext c1;
  tv1::GetRunMetricsRequest metrics_request;
  metrics_request.set_run_id(id);
  tv1::GetRunMetricsResponse metrics;
  ASSERT_TRUE(stub_->GetRunMetrics(&c1, metrics_request, &metrics).ok());
  grpc::ClientContext c2;
  tv1::ListCheckpointsRequest checkpoints_request;
  checkpoints_request.set_run_id(id);
  tv1::ListCheckpointsResponse checkpoints;
  ASSERT_TRUE(stub_->ListCheckpoints(&c2, checkpoints_request, &checkpoints).ok());
  ASSERT_EQ(checkpoints.checkpoints_size(), metrics.points_size());
  EXPECT_EQ(checkpoints.checkpoints(0).role(), common::v1::ROLE_APPROACH);
  EXPECT_EQ(checkpoints.checkpoints(0).checksum().size(), 16u);

  grpc::ClientContext c3;
  tv1::GetTrainingRunRequest get;
  get.set_run_id(id);
  tv1::GetTrainingRunResponse got;
  ASSERT_TRUE(stub_->GetTrainingRun(&c3, get, &got).ok());
  EXPECT_EQ(got.run().latest_checkpoint_id(),
            checkpoints.checkpoints(checkpoints.checkpoints_size() - 1).checkpoint_id());
  EXPECT_TRUE(got.run().has_finish_time());
  EXPECT_NE(got.run().config_json().find("\"hidden\":[32,32]"), std::string::npos);
  EXPECT_NE(got.run().config_json().find("\"preset\":\"ours\""), std::string::npos)
      << "no preset asked for: the default";
}

// Unset fields take the preset's values; fields the request sets win.
TEST_F(TrainingServiceTest, APresetFillsTheUnsetFieldsAndTheRequestsOwnWin) {
  start("approach");
  tv1::CreateTrainingRunRequest r = small_request();
  r.set_preset("paper");
  tv1::CreateTrainingRunResponse created;
  ASSERT_TRUE(create(r, created).ok());
  const auto config = nlohmann::json::parse(created.run().config_json()).at("spec");
  EXPECT_EQ(config.at("preset"), "paper");
  EXPECT_EQ(config.at("scripted_gripper"), true) << "the paper's gripper";
  EXPECT_EQ(config.at("ddpg").at("demo_bc_weight"), 0.0);
  EXPECT_EQ(config.at("ddpg").at("updates_per_transition"), 0.25) << "set by the request";
  EXPECT_EQ(config.at("stop").at("eval_interval_steps"), 200) << "set by the request";
  EXPECT_EQ(config.at("stop").at("target_success"), 1.0) << "set by the request";
}

// Each case's change to `base` is refused with its code and a message naming the field,
// and no run is stored.
void TrainingServiceTest::expect_refused(const std::vector<BadCreate>& cases,
                                         const tv1::CreateTrainingRunRequest& base) {
  for (const auto& c : cases) {
    tv1::CreateTrainingRunRequest r = base;
    c.change(r);
    tv1::CreateTrainingRunResponse out;
    const grpc::Status status = create(r, out);
    EXPECT_EQ(status.error_code(), c.code) << c.name << ": " << status.error_message();
    EXPECT_NE(status.error_message().find(c.message), std::string::npos)
        << c.name << ": " << status.error_message();
  }
  EXPECT_EQ(run_count(), 0u);
}

TEST_F(TrainingServiceTest, BadCreateRequestsAreRefusedNamingTheFieldAndStoreNothing) {
  start("approach");
  const std::vector<BadCreate> cases{
      {"other role", [](auto& r) { r.set_role(common::v1::ROLE_RETRACT); },
       grpc::StatusCode::INVALID_ARGUMENT, "role: expected \"approach\""},
      {"no role", [](auto& r) { r.set_role(common::v1::ROLE_UNSPECIFIED); },
       grpc::StatusCode::INVALID_ARGUMENT, "role"},
      {"no algorithm", [](auto& r) { r.set_algorithm(tv1::ALGORITHM_UNSPECIFIED); },
       grpc::StatusCode::INVALID_ARGUMENT, "algorithm"},
      {"a3c for an expert", [](auto& r) { r.set_algorithm(tv1::ALGORITHM_A3C); },
       grpc::StatusCode::INVALID_ARGUMENT, "algorithm: expected one of ddpg_her, bc"},
      {"unknown robot", [](auto& r) { r.set_robot(static_cast<common::v1::Robot>(77)); },
       grpc::StatusCode::INVALID_ARGUMENT, "robot"},
      {"NaN learning rate",
       [](auto& r) { r.mutable_ddpg()->set_actor_learning_rate(std::nan("")); },
       grpc::StatusCode::INVALID_ARGUMENT, "actor_learning_rate"},
      {"target above 1", [](auto& r) { r.mutable_stop()->set_target_success(1.5); },
       grpc::StatusCode::INVALID_ARGUMENT, "target_success"},
      {"batch above buffer", [](auto& r) { r.mutable_ddpg()->set_buffer_size(8); },
       grpc::StatusCode::INVALID_ARGUMENT, "batch_size"},
      {"unknown parent", [](auto& r) { r.set_parent_checkpoint_id(99); },
       grpc::StatusCode::NOT_FOUND, "checkpoint 99"},
      {"negative parent", [](auto& r) { r.set_parent_checkpoint_id(-1); },
       grpc::StatusCode::INVALID_ARGUMENT, "parent_checkpoint_id"},
      {"prefix for approach", [](auto& r) { r.add_prefix_checkpoint_ids(1); },
       grpc::StatusCode::INVALID_ARGUMENT, "prefix_checkpoint_ids: expected 0 ids"},
      {"experts for an expert", [](auto& r) { r.add_expert_checkpoint_ids(1); },
       grpc::StatusCode::INVALID_ARGUMENT, "expert_checkpoint_ids"},
      {"NaN cloning weight", [](auto& r) { r.mutable_ddpg()->set_demo_bc_weight(std::nan("")); },
       grpc::StatusCode::INVALID_ARGUMENT, "demo_bc_weight: expected a non-negative number"},
      {"unknown preset", [](auto& r) { r.set_preset("fast"); }, grpc::StatusCode::INVALID_ARGUMENT,
       "preset: expected one of [\"paper\",\"ours\",\"ours+demos\"], got \"fast\""},
  };
  expect_refused(cases, small_request());
}

// The choreographer's A3C fields reach validation from the proto: bad ones are refused
// by name and nothing is stored.
TEST_F(TrainingServiceTest, BadChoreographerSettingsAreRefusedNamingTheField) {
  start("hlc");
  const std::vector<BadCreate> cases{
      {"NaN chain prior", [](auto& r) { r.mutable_a3c()->set_chain_prior(std::nan("")); },
       grpc::StatusCode::INVALID_ARGUMENT, "network.chain_prior: expected a logit bonus"},
      {"exploring starts above 1", [](auto& r) { r.mutable_a3c()->set_exploring_starts(2.0); },
       grpc::StatusCode::INVALID_ARGUMENT, "exploring_starts: expected a fraction in [0, 1]"},
  };
  tv1::CreateTrainingRunRequest hlc = small_request();
  hlc.set_role(common::v1::ROLE_HLC);
  hlc.set_algorithm(tv1::ALGORITHM_A3C);
  expect_refused(cases, hlc);
}

TEST_F(TrainingServiceTest, UnknownIdsAndBadPagingAreRefused) {
  start("approach");
  grpc::ClientContext c1;
  tv1::GetTrainingRunRequest get;
  get.set_run_id(12345);
  tv1::GetTrainingRunResponse got;
  EXPECT_EQ(stub_->GetTrainingRun(&c1, get, &got).error_code(), grpc::StatusCode::NOT_FOUND);
  grpc::ClientContext c2;
  get.set_run_id(0);
  EXPECT_EQ(stub_->GetTrainingRun(&c2, get, &got).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  grpc::ClientContext c3;
  tv1::ListTrainingRunsRequest list;
  list.set_page_size(5000);
  tv1::ListTrainingRunsResponse listed;
  EXPECT_EQ(stub_->ListTrainingRuns(&c3, list, &listed).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  grpc::ClientContext c4;
  list.set_page_size(10);
  list.set_page_token("not-a-token");
  const grpc::Status bad_token = stub_->ListTrainingRuns(&c4, list, &listed);
  EXPECT_EQ(bad_token.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad_token.error_message().find("page_token"), std::string::npos);
  grpc::ClientContext c5;
  tv1::GetRunMetricsRequest metrics;
  metrics.set_run_id(777);
  tv1::GetRunMetricsResponse points;
  EXPECT_EQ(stub_->GetRunMetrics(&c5, metrics, &points).error_code(), grpc::StatusCode::NOT_FOUND);
  grpc::ClientContext c6;
  tv1::CancelTrainingRunRequest cancel;
  cancel.set_run_id(777);
  tv1::CancelTrainingRunResponse cancelled;
  EXPECT_EQ(stub_->CancelTrainingRun(&c6, cancel, &cancelled).error_code(),
            grpc::StatusCode::NOT_FOUND);
}

TEST_F(TrainingServiceTest, ListPagesNewestFirst) {
  start("approach");
  std::vector<std::int64_t> ids;
  for (int i = 0; i < 3; ++i) {
    tv1::CreateTrainingRunResponse created;
    ASSERT_TRUE(create(small_request(1'000'000), created).ok());
    ids.push_back(created.run().run_id());
  }
  std::vector<std::int64_t> seen;
  std::string token;
  do {
    grpc::ClientContext context;
    tv1::ListTrainingRunsRequest request;
    request.set_page_size(2);
    request.set_page_token(token);
    tv1::ListTrainingRunsResponse page;
    ASSERT_TRUE(stub_->ListTrainingRuns(&context, request, &page).ok());
    for (const auto& run : page.runs()) seen.push_back(run.run_id());
    token = page.next_page_token();
  } while (!token.empty());
  EXPECT_EQ(seen, (std::vector<std::int64_t>{ids[2], ids[1], ids[0]}));
  for (auto id : ids) manager_->cancel(id);
}

// An imported checkpoint is a finished run without a training spec; a file name with a
// quote in it once made its config invalid JSON and broke the whole listing.
TEST_F(TrainingServiceTest, ImportedRunsAreListedBesideTrainedOnes) {
  start("approach");
  const std::filesystem::path file = dir_.file("my \"best\" approach.ckpt");
  std::ofstream(file) << "weights";
  {
    store::RunStore store(dir_.file("pnp.db"));
    store::import_checkpoint(store, {"approach", "ddpg_her", "fetch", "block", file}, false);
  }
  grpc::ClientContext context;
  tv1::ListTrainingRunsResponse listed;
  const auto status = stub_->ListTrainingRuns(&context, {}, &listed);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(listed.runs_size(), 1);
  EXPECT_EQ(listed.runs(0).state(), tv1::RUN_STATE_SUCCEEDED);
  EXPECT_EQ(listed.runs(0).max_steps(), 0) << "an import has no training spec";
  EXPECT_GT(listed.runs(0).latest_checkpoint_id(), 0);
}

TEST_F(TrainingServiceTest, CancelEndsTheWatchAndASecondCancelIsAPreconditionFailure) {
  start("approach");
  tv1::CreateTrainingRunResponse created;
  ASSERT_TRUE(create(small_request(1'000'000), created).ok());
  const std::int64_t id = created.run().run_id();
  grpc::ClientContext c1;
  tv1::CancelTrainingRunRequest cancel;
  cancel.set_run_id(id);
  tv1::CancelTrainingRunResponse out;
  ASSERT_TRUE(stub_->CancelTrainingRun(&c1, cancel, &out).ok());
  const auto messages = watch(id);
  EXPECT_EQ(messages.back().run().state(), tv1::RUN_STATE_CANCELLED);
  grpc::ClientContext c2;
  EXPECT_EQ(stub_->CancelTrainingRun(&c2, cancel, &out).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
}

TEST_F(TrainingServiceTest, AWatchHonoursItsDeadline) {
  start("approach");
  tv1::CreateTrainingRunResponse created;
  ASSERT_TRUE(create(small_request(1'000'000), created).ok());
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(300));
  tv1::WatchTrainingRunRequest request;
  request.set_run_id(created.run().run_id());
  auto reader = stub_->WatchTrainingRun(&context, request);
  for (tv1::WatchTrainingRunResponse m; reader->Read(&m);) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  manager_->cancel(created.run().run_id());
}

TEST_F(TrainingServiceTest, TheChoreographerTrainsOverTheExpertsItIsGiven) {
  start("hlc");
  // Three (untrained) experts in the store: the mechanics, not the learning, are tested.
  std::vector<std::int64_t> experts;
  {
    store::RunStore store(dir_.file("pnp.db"));
    for (const char* role : {"approach", "manipulate", "retract"}) {
      rl::DdpgHerConfig config;
      config.hidden = {16};
      Rng rng(1);
      rl::DdpgHerAgent agent(config, rng);
      const auto blob = rl::save_expert(
          {role, "ddpg_her", "fetch", "block", "paper", config.hidden, config.hidden_activation,
           true, 200, 5, 0.01, 0, 0, 1, "test"},
          agent.actor(), nullptr, agent.observation_normalizer(), agent.goal_normalizer());
      const auto run =
          store.create_run({role, "ddpg_her", "fetch", "block", 1, "{}", "", std::nullopt});
      experts.push_back(store.save_checkpoint(run.id, 0, 0, blob).id);
    }
  }
  tv1::CreateTrainingRunRequest r;
  r.set_role(common::v1::ROLE_HLC);
  r.set_algorithm(tv1::ALGORITHM_A3C);
  r.set_robot(common::v1::ROBOT_FETCH);
  r.set_object(common::v1::OBJECT_SHAPE_BLOCK);
  r.mutable_stop()->set_max_steps(300);
  r.mutable_stop()->set_eval_interval_steps(150);
  r.mutable_stop()->set_eval_episodes(4);
  tv1::CreateTrainingRunResponse created;
  r.add_expert_checkpoint_ids(experts[1]);  // in the wrong slot
  r.add_expert_checkpoint_ids(experts[0]);
  r.add_expert_checkpoint_ids(experts[2]);
  const grpc::Status wrong_slot = create(r, created);
  EXPECT_EQ(wrong_slot.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(wrong_slot.error_message().find("expert_checkpoint_ids[0]: expected a checkpoint of "
                                            "role approach"),
            std::string::npos)
      << wrong_slot.error_message();
  r.clear_expert_checkpoint_ids();
  for (auto id : experts) r.add_expert_checkpoint_ids(id);
  ASSERT_TRUE(create(r, created).ok());
  const auto messages = watch(created.run().run_id());
  EXPECT_EQ(messages.back().run().state(), tv1::RUN_STATE_SUCCEEDED)
      << messages.back().run().error();
  EXPECT_GE(messages.back().run().env_steps(), 300);
}

}  // namespace
}  // namespace pnp::services
