// What only the store behind its service has: checkpoint bytes checked on arrival, the
// promotions streamed to watchers, refusals at the boundary, and a store server that is gone.
#include <condition_variable>
#include <mutex>
#include <thread>

#include "common/checksum.h"
#include "services/store/remote_audit.h"
#include "store/audit_trail.h"
#include "tests/store_contract/store_contract.h"

namespace pnp::store {
namespace {

using namespace std::chrono_literals;
namespace v1 = ::pnp::store::v1;

class StoreService : public StoreContract {
 protected:
  std::unique_ptr<v1::StoreService::Stub> stub() {
    return v1::StoreService::NewStub(
        grpc::CreateChannel(address_, grpc::InsecureChannelCredentials()));
  }
  // Streams a SaveCheckpoint of `bytes` declared as `declared` (size and checksum).
  grpc::Status save_raw(std::int64_t run_id, const std::string& bytes,
                        const std::string& declared) {
    grpc::ClientContext context;
    v1::CheckpointInfo info;
    auto writer = stub()->SaveCheckpoint(&context, &info);
    v1::SaveCheckpointRequest message;
    auto& header = *message.mutable_header();
    header.set_run_id(run_id);
    header.set_size_bytes(static_cast<std::int64_t>(declared.size()));
    header.set_checksum(fnv1a64_hex(
        std::span(reinterpret_cast<const std::uint8_t*>(declared.data()), declared.size())));
    header.mutable_evaluated()->set_env_steps(100);
    writer->Write(message);
    message.Clear();
    message.set_chunk(bytes);
    writer->Write(message);
    writer->WritesDone();
    return writer->Finish();
  }
};

TEST_P(StoreService, BytesThatDoNotMatchTheirChecksumOrSizeAreRefusedAndNothingIsStored) {
  auto store = open();
  const auto run = store->create_run(spec());
  const grpc::Status flipped = save_raw(run.id, "abcdeX", "abcdef");
  EXPECT_EQ(flipped.error_code(), grpc::StatusCode::DATA_LOSS) << flipped.error_message();
  EXPECT_NE(flipped.error_message().find("checksum"), std::string::npos);
  const grpc::Status longer = save_raw(run.id, "abcdefg", "abcdef");
  EXPECT_EQ(longer.error_code(), grpc::StatusCode::DATA_LOSS) << longer.error_message();
  const grpc::Status shorter = save_raw(run.id, "abc", "abcdef");
  EXPECT_EQ(shorter.error_code(), grpc::StatusCode::DATA_LOSS) << shorter.error_message();
  EXPECT_TRUE(store->checkpoints(run.id).empty());
  EXPECT_TRUE(save_raw(run.id, "abcdef", "abcdef").ok());
  EXPECT_EQ(store->checkpoints(run.id).size(), 1u);
}

TEST_P(StoreService, RefusalsAtTheBoundaryNameTheField) {
  grpc::ClientContext context;
  v1::CheckpointInfo info;
  auto writer = stub()->SaveCheckpoint(&context, &info);
  v1::SaveCheckpointRequest chunk_first;
  chunk_first.set_chunk("xyz");
  writer->Write(chunk_first);
  writer->WritesDone();
  const grpc::Status no_header = writer->Finish();
  EXPECT_EQ(no_header.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(no_header.error_message().find("header"), std::string::npos);

  grpc::ClientContext claim_context;
  v1::ClaimNextRunRequest claim;
  claim.set_role("approach");
  claim.set_owner("a");
  claim.set_lease_ms(0);
  v1::ClaimNextRunResponse claimed;
  const grpc::Status bad_lease = stub()->ClaimNextRun(&claim_context, claim, &claimed);
  EXPECT_EQ(bad_lease.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad_lease.error_message().find("lease_ms"), std::string::npos);

  grpc::ClientContext state_context;
  v1::SetRunStateRequest set;
  set.set_run_id(1);
  set.set_state("paused");
  v1::RunResponse run;
  const grpc::Status bad_state = stub()->SetRunState(&state_context, set, &run);
  EXPECT_EQ(bad_state.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad_state.error_message().find("state"), std::string::npos);
}

// A watcher sees the set at once, then each change: promoted through the service (at
// once) or written to the file by another process (within the service's recheck).
TEST_P(StoreService, WatchersSeeEveryChangeOfThePromotions) {
  auto store = open();
  const auto run = store->create_run(spec("hlc"));
  const auto first = store->save_checkpoint(run.id, 100, 0.5, std::vector<std::uint8_t>{1});
  const auto second = store->save_checkpoint(run.id, 200, 0.6, std::vector<std::uint8_t>{2});
  std::mutex mutex;
  std::condition_variable seen;
  std::vector<std::vector<Promotion>> updates;
  grpc::ClientContext context;
  grpc::Status ended;
  std::thread watcher([&, remote = open()] {
    ended = dynamic_cast<services::RemoteStore&>(*remote).watch_promotions(
        context, [&](std::vector<Promotion> promotions) {
          std::lock_guard lock(mutex);
          updates.push_back(std::move(promotions));
          seen.notify_all();
          return true;
        });
  });
  const auto wait_for = [&](std::size_t n) {
    std::unique_lock lock(mutex);
    return seen.wait_for(lock, 10s, [&] { return updates.size() >= n; });
  };
  ASSERT_TRUE(wait_for(1));
  EXPECT_TRUE(updates[0].empty());
  store->promote(first.id);
  ASSERT_TRUE(wait_for(2));
  ASSERT_EQ(updates[1].size(), 1u);
  EXPECT_EQ(updates[1][0].checkpoint_id, first.id);
  direct().promote(second.id);  // behind the service's back
  ASSERT_TRUE(wait_for(3));
  EXPECT_EQ(updates[2][0].checkpoint_id, second.id);
  context.TryCancel();
  watcher.join();
  EXPECT_EQ(ended.error_code(), grpc::StatusCode::CANCELLED);
}

TEST_P(StoreService, AStoreServerThatIsGoneIsUnavailable) {
  auto store = open();
  store->create_run(spec());
  service_->stop_watches();
  server_->shutdown(0ms);
  server_.reset();
  EXPECT_EQ(code_of([&] { store->list_runs(); }), ErrorCode::kUnavailable);
  EXPECT_EQ(code_of([&] { store->create_run(spec()); }), ErrorCode::kUnavailable);
}

// A server without the file (--store) audits through the store server: its trail's
// batches land in the store's audit table, in order, and read back through the service.
TEST_P(StoreService, AuditRecordsOfAServerWithoutTheFileLandInTheStoresTrail) {
  std::vector<std::string> problems;
  auto trail = services::open_remote_audit_trail(address_, {}, "inference");
  for (int k = 1; k <= 3; ++k) {
    trail->append({0, 1000 + k, "inference", "ops", "ipv4:127.0.0.1:5",
                   "/pnp.policy.v1.Policy"
                   "Service/PromoteCheckpoint",
                   "{\"checkpoint_ids\":[" + std::to_string(k) + "]}", "OK"});
  }
  trail->flush();
  const auto read = services::read_remote_audit(address_, {}, 0, 10);
  ASSERT_EQ(read.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(read[k].ts_ms, 1001 + static_cast<std::int64_t>(k));
    EXPECT_EQ(read[k].principal, "ops");
    EXPECT_EQ(read[k].code, "OK");
    EXPECT_GT(read[k].id, 0);
  }
  EXPECT_EQ(read_audit(path_, 1002, 10).size(), 2u);  // the same table, in the file
  EXPECT_EQ(services::read_remote_audit(address_, {}, 0, 1).front().ts_ms, 1003);  // newest
}

// More records than one message holds (the service caps messages at 512 KiB): they travel
// in several AppendAudit requests and come back in several ReadAudit pages, all in order.
TEST_P(StoreService, AnAuditTrailLargerThanAMessageGoesAndComesBackWhole) {
  auto trail = services::open_remote_audit_trail(address_, {}, "approach");
  constexpr int kRecords = 400;  // about 800 KB of requests
  for (int k = 0; k < kRecords; ++k) {
    trail->append({0, 5000 + k, "approach", "ops", "peer", "/pnp.train.v1.TrainingService/X",
                   std::string(2000, static_cast<char>('a' + k % 26)), "OK"});
  }
  trail->flush();
  const auto read = services::read_remote_audit(address_, {}, 0, 1000);
  ASSERT_EQ(read.size(), static_cast<std::size_t>(kRecords));
  for (std::size_t k = 0; k < read.size(); ++k)
    EXPECT_EQ(read[k].ts_ms, 5000 + static_cast<std::int64_t>(k)) << k;
  // A limit counts from the newest.
  const auto newest = services::read_remote_audit(address_, {}, 0, 250);
  ASSERT_EQ(newest.size(), 250u);
  EXPECT_EQ(newest.front().ts_ms, 5000 + kRecords - 250);
  EXPECT_EQ(newest.back().ts_ms, 5000 + kRecords - 1);
}

TEST_P(StoreService, AuditRefusalsNameTheFieldAndWriteNothing) {
  try {
    services::read_remote_audit(address_, {}, 0, 0);
    ADD_FAILURE() << "a limit of 0 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("limit"), std::string::npos) << e.what();
  }
  grpc::ClientContext context;
  v1::AppendAuditRequest request;
  auto* good = request.add_records();
  good->set_ts_ms(5);
  good->set_rpc("/x");
  good->set_code("OK");
  auto* bad = request.add_records();
  *bad = *good;
  bad->set_ts_ms(0);
  v1::AppendAuditResponse response;
  const grpc::Status status = stub()->AppendAudit(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("records[1].ts_ms"), std::string::npos)
      << status.error_message();
  EXPECT_TRUE(read_audit(path_, 0, 10).empty()) << "half of a refused batch was written";
}

INSTANTIATE_TEST_SUITE_P(Remote, StoreService, ::testing::Values(Backend::kRemote), backend_name);

}  // namespace
}  // namespace pnp::store
