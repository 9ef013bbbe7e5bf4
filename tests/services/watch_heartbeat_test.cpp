// Watches are closed for idleness like every other stream, and a quiet watch stays open by
// sending heartbeats: in process, the store's WatchPromotions and the training service's
// WatchTrainingRun behind stream limits with a short idle timeout, through real stubs.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>

#include "pnp/store/v1/store_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "rl/checkpoint_probe.h"
#include "services/common/server_runtime.h"
#include "services/common/stream_limits.h"
#include "services/store/store_service.h"
#include "services/train/training_service.h"
#include "tests/core/training/small_runs.h"
#include "training/run_manager.h"

namespace pnp::services {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A third of it between heartbeats: wide margins for a loaded 2-core machine.
constexpr auto kIdleTimeout = 1500ms;
constexpr auto kWatchFor = 5s;  // more than three idle timeouts

std::shared_ptr<grpc::Channel> loopback(const ServerRuntime& runtime) {
  return grpc::CreateChannel("127.0.0.1:" + std::to_string(runtime.port()),
                             grpc::InsecureChannelCredentials());
}

struct Counts {
  int changes = 0;
  int heartbeats = 0;
};

TEST(WatchHeartbeat, AQuietPromotionsWatchOutlivesTheIdleTimeoutOnHeartbeats) {
  const training::testing::ScratchDir dir("watch_heartbeat_promotions");
  StreamLimits limits({.max_streams = 4, .idle_timeout = kIdleTimeout}, "store");
  StoreServiceImpl service(dir.file("pnp.db"), rl::probe_checkpoint, &limits);
  ServerRuntime runtime(ServerConfig{.address = "127.0.0.1:0",
                                     .services = {&service},
                                     .service_names = {"pnp.store.v1.StoreService"}});
  const auto stub = store::v1::StoreService::NewStub(loopback(runtime));

  grpc::ClientContext context;
  auto reader = stub->WatchPromotions(&context, {});
  Counts counts;
  const auto until = Clock::now() + kWatchFor;
  for (store::v1::PromotionsResponse m; Clock::now() < until && reader->Read(&m);)
    ++(m.heartbeat() ? counts.heartbeats : counts.changes);
  EXPECT_EQ(counts.changes, 1);  // the current (empty) set, once
  EXPECT_GE(counts.heartbeats, 3);
  EXPECT_EQ(limits.closed_for_idleness(), 0u);
  EXPECT_EQ(limits.open_streams(), 1);
  context.TryCancel();
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  service.stop_watches();
  runtime.shutdown(100ms);
}

TEST(WatchHeartbeat, AQuietTrainingWatchOutlivesTheIdleTimeoutAndEndsWithItsRun) {
  const training::testing::ScratchDir dir("watch_heartbeat_training");
  training::RunManager manager({dir.file("pnp.db"), "approach", "test", 1});
  StreamLimits limits({.max_streams = 4, .idle_timeout = kIdleTimeout}, "approach");
  TrainingServiceImpl service(manager, &limits);
  ServerRuntime runtime(ServerConfig{.address = "127.0.0.1:0",
                                     .services = {&service},
                                     .service_names = {"pnp.train.v1.TrainingService"}});
  const auto stub = train::v1::TrainingService::NewStub(loopback(runtime));

  // A run that evaluates far less often than the watch lasts: nothing to report meanwhile.
  train::v1::CreateTrainingRunRequest request;
  request.set_role(common::v1::ROLE_APPROACH);
  request.set_algorithm(train::v1::ALGORITHM_DDPG_HER);
  request.set_robot(common::v1::ROBOT_FETCH);
  request.set_object(common::v1::OBJECT_SHAPE_BLOCK);
  request.set_seed(3);
  request.mutable_stop()->set_max_steps(10'000'000);
  request.mutable_stop()->set_eval_interval_steps(5'000'000);
  request.mutable_ddpg()->add_hidden(16);
  train::v1::CreateTrainingRunResponse created;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(stub->CreateTrainingRun(&context, request, &created).ok());
  }
  const std::int64_t id = created.run().run_id();

  grpc::ClientContext context;
  train::v1::WatchTrainingRunRequest watch;
  watch.set_run_id(id);
  auto reader = stub->WatchTrainingRun(&context, watch);
  Counts counts;
  const auto until = Clock::now() + kWatchFor;
  train::v1::WatchTrainingRunResponse m;
  for (; Clock::now() < until && reader->Read(&m);) {
    ++(m.heartbeat() ? counts.heartbeats : counts.changes);
    if (m.heartbeat()) {
      EXPECT_FALSE(m.has_metric());
    }
  }
  EXPECT_GE(counts.heartbeats, 3);
  EXPECT_EQ(limits.closed_for_idleness(), 0u);
  // Cancelling the run ends the watch with the final state, not a heartbeat.
  manager.cancel(id);
  while (reader->Read(&m)) {
  }
  EXPECT_FALSE(m.heartbeat());
  EXPECT_EQ(m.run().state(), train::v1::RUN_STATE_CANCELLED);
  EXPECT_TRUE(reader->Finish().ok());
  runtime.shutdown(500ms);
}

}  // namespace
}  // namespace pnp::services
