// A client cannot exhaust a server with streams: in process, the inference service over a
// store serving the checked-in hierarchy, with stream limits, called through real stubs.
#include "services/common/stream_limits.h"

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <thread>

#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"

namespace pnp::services {
namespace {

namespace fs = std::filesystem;
namespace pv1 = policy::v1;
using namespace std::chrono_literals;

class StreamLimitsTest : public ::testing::Test {
 protected:
  void start(StreamLimitOptions options) {
    dir_ = fs::temp_directory_path() / ("pnp_stream_limits_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::string db = (dir_ / "pnp.db").string();
    {
      store::RunStore store(db);
      store::import_hierarchy(store, PNP_SOURCE_DIR "/tests/data/panda_block", "panda", "block");
    }
    limits_ = std::make_unique<StreamLimits>(options, "test");
    service_ =
        std::make_unique<PolicyServiceImpl>(db, serving::PolicyKind::kHierarchy, limits_.get());
    runtime_ = std::make_unique<ServerRuntime>(
        ServerConfig{.address = "127.0.0.1:0",
                     .services = {service_.get()},
                     .service_names = {"pnp.policy.v1.PolicyService"}});
    stub_ = pv1::PolicyService::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string(runtime_->port()), grpc::InsecureChannelCredentials()));
  }
  void TearDown() override {
    if (runtime_) runtime_->shutdown(100ms);
    runtime_.reset();
    service_.reset();
    limits_.reset();
    fs::remove_all(dir_);
  }

  // An open session that sends nothing: its handler waits in Read.
  struct IdleSession {
    grpc::ClientContext context;
    std::unique_ptr<
        grpc::ClientReaderWriter<pv1::PredictSessionRequest, pv1::PredictSessionResponse>>
        stream;
  };
  std::unique_ptr<IdleSession> open_session() {
    auto session = std::make_unique<IdleSession>();
    session->context.set_deadline(std::chrono::system_clock::now() + 120s);
    session->stream = stub_->PredictSession(&session->context);
    return session;
  }

  static pv1::PredictSessionRequest step_request() {
    pv1::PredictSessionRequest request;
    for (int i = 0; i < 25; ++i) request.mutable_observation()->add_values(0.1);
    request.mutable_goal()->set_x_m(0.1);
    request.mutable_goal()->set_y_m(0.1);
    request.mutable_goal()->set_z_m(0.1);
    return request;
  }

  grpc::Status predict() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 30s);
    pv1::PredictRequest request;
    *request.mutable_observation() = step_request().observation();
    *request.mutable_goal() = step_request().goal();
    pv1::PredictResponse response;
    return stub_->Predict(&context, request, &response);
  }

  std::size_t admitted() const {
    return static_cast<std::size_t>(limits_->open_streams()) + limits_->closed_for_idleness();
  }

  bool wait_for_open_streams(int n) {
    for (int i = 0; i < 3000 && limits_->open_streams() != n; ++i)
      std::this_thread::sleep_for(10ms);
    return limits_->open_streams() == n;
  }

  fs::path dir_;
  std::unique_ptr<StreamLimits> limits_;
  std::unique_ptr<PolicyServiceImpl> service_;
  std::unique_ptr<ServerRuntime> runtime_;
  std::unique_ptr<pv1::PolicyService::Stub> stub_;
};

TEST_F(StreamLimitsTest, TwoHundredIdleSessionsNeitherBlockAPredictNorStayOpen) {
  start({.max_streams = 256, .idle_timeout = 3s});
  std::vector<std::unique_ptr<IdleSession>> sessions;
  for (int i = 0; i < 200; ++i) sessions.push_back(open_session());
  // Every one admitted: open, or (in a build slow enough to take seconds to open 200, such
  // as under ThreadSanitizer) already closed by the idle timeout, never refused.
  for (int i = 0; i < 3000 && admitted() != 200; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_EQ(admitted(), 200u) << limits_->open_streams() << " open, "
                              << limits_->closed_for_idleness() << " closed for idleness";
  const grpc::Status fresh = predict();
  EXPECT_TRUE(fresh.ok()) << fresh.error_message();
  // The idle timeout closes every one of them (the clients never close them): each client
  // sees its call cancelled.
  for (auto& session : sessions)
    EXPECT_EQ(session->stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_TRUE(wait_for_open_streams(0));
  EXPECT_EQ(limits_->closed_for_idleness(), 200u);
  EXPECT_TRUE(predict().ok());
}

TEST_F(StreamLimitsTest, BeyondTheLimitANewStreamIsResourceExhaustedNamingTheFlag) {
  start({.max_streams = 3, .idle_timeout = 60s});
  std::vector<std::unique_ptr<IdleSession>> sessions;
  for (int i = 0; i < 3; ++i) sessions.push_back(open_session());
  ASSERT_TRUE(wait_for_open_streams(3));
  auto extra = open_session();
  const grpc::Status refused = extra->stream->Finish();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(refused.error_message().find("--max-streams"), std::string::npos)
      << refused.error_message();
  EXPECT_TRUE(predict().ok()) << "unary calls are not streams";
  // One ends: a new one is admitted again.
  sessions[0]->stream->WritesDone();
  EXPECT_TRUE(sessions[0]->stream->Finish().ok());
  ASSERT_TRUE(wait_for_open_streams(2));
  auto again = open_session();
  const auto request = step_request();
  ASSERT_TRUE(again->stream->Write(request));
  pv1::PredictSessionResponse response;
  EXPECT_TRUE(again->stream->Read(&response));
  for (auto& session : sessions) session->context.TryCancel();
  again->context.TryCancel();
}

TEST_F(StreamLimitsTest, ASessionThatKeepsTalkingIsNeverClosed) {
  start({.max_streams = 8, .idle_timeout = 2s});
  auto session = open_session();
  const auto request = step_request();
  pv1::PredictSessionResponse response;
  // Twice the idle timeout, a step every 100 ms (a policy period is 40 ms).
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(session->stream->Write(request)) << "closed after " << k << " steps";
    ASSERT_TRUE(session->stream->Read(&response)) << "closed after " << k << " steps";
    std::this_thread::sleep_for(100ms);
  }
  session->stream->WritesDone();
  EXPECT_TRUE(session->stream->Finish().ok());
  EXPECT_EQ(limits_->closed_for_idleness(), 0u);
}

TEST(StreamLimitOptionsTest, NonsenseLimitsAreRefusedNamingTheFlag) {
  EXPECT_THROW(StreamLimits({.max_streams = 0, .idle_timeout = 1s}, "t"), Error);
  EXPECT_THROW(StreamLimits({.max_streams = 1, .idle_timeout = 0ms}, "t"), Error);
}

}  // namespace
}  // namespace pnp::services
