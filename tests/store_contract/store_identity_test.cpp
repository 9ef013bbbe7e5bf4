// The store takes who is writing from the authenticated channel, never from the message:
// a real pnp-store-server service (with the checkpoint probe pnp-store-server runs) behind
// TLS and an authorization policy, called through real stubs by principals of their own.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "common/error.h"
#include "pnp/store/v1/store_service.grpc.pb.h"
#include "rl/checkpoint_probe.h"
#include "security/auth_policy.h"
#include "security/sha256.h"
#include "services/common/server_runtime.h"
#include "services/common/stream_limits.h"
#include "services/common/transport_security.h"
#include "services/store/checkpoint_chunks.h"
#include "services/store/remote_store.h"
#include "services/store/store_service.h"
#include "store/audit_trail.h"
#include "store/run_store.h"
#include "support/refusal.h"

namespace pnp::services {
namespace {

namespace fs = std::filesystem;
namespace v1 = ::pnp::store::v1;

// Who calls the store, with the classes a deployment gives them (docs/RELIABILITY.md).
// The approach trainer is bound to its role, as deploy/ binds each trainer; the retract
// one is not (a policy without "roles": every role).
struct Principal {
  const char* name;
  const char* classes;
  const char* roles = nullptr;
};
constexpr Principal kPrincipals[] = {
    {"ops", R"("reader", "agent", "operator")"},
    {"inference", R"("reader", "service", "delegate")"},
    {"approach", R"("reader", "agent", "service")", R"("approach")"},
    {"retract", R"("reader", "agent", "service")"},
    {"dashboard", R"("reader")"},
};

using pnp::testing::code_of;

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::uint8_t> checked_in(const std::string& role) {
  return read_bytes(fs::path(PNP_TEST_DATA_DIR) / "panda_block" / (role + ".ckpt"));
}

// A Panda block run of `role`, as a trainer creates it.
store::RunSpec spec_of(const std::string& role) {
  store::RunSpec spec;
  spec.role = role;
  spec.algorithm = role == "hlc" ? "a3c" : "ddpg_her";
  spec.robot = "panda";
  spec.object = "block";
  return spec;
}

class StoreIdentity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("pnp_store_identity_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    const std::string command = std::string(PNP_SOURCE_DIR) + "/scripts/make-dev-certs --out " +
                                (dir_ / "certs").string() + " 2>/dev/null";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    // The policy of this test: a token per principal, stored hashed.
    std::string policy = R"({"principals": [)";
    for (const Principal& p : kPrincipals) {
      const std::string token = std::string("token-of-") + p.name;
      std::ofstream(token_file(p.name)) << token;
      if (policy.back() == '}') policy += ",";
      policy += std::string(R"({"name": ")") + p.name + R"(", "token_sha256": ")" +
                security::sha256_hex(token) + R"(", "classes": [)" + p.classes + "]" +
                (p.roles ? std::string(R"(, "roles": [)") + p.roles + "]" : std::string()) + "}";
    }
    std::ofstream(dir_ / "policy.json") << policy << "]}";
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string token_file(const std::string& who) {
    return (dir_ / (who + ".token")).string();
  }

  void SetUp() override {
    db_ = (dir_ /
           (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".db"))
              .string();
    // Three streams in all: a quarter of them (one) per principal.
    limits_ = std::make_unique<StreamLimits>(StreamLimitOptions{.max_streams = 3}, "store");
    // Room for the checked-in checkpoints (under 1 MiB each), three open runs per principal.
    service_ = std::make_unique<StoreServiceImpl>(
        db_, rl::probe_checkpoint, limits_.get(), store::DatabaseOptions{},
        store::StoreQuotas{.max_checkpoint_bytes = 4 << 20,
                           .max_run_checkpoint_bytes = 16 << 20,
                           .max_open_runs_per_principal = 3},
        /*max_transfer_bytes=*/8 << 20);
    ServerSecurity security;
    security.tls = {(dir_ / "certs" / "server.pem").string(),
                    (dir_ / "certs" / "server.key").string(), "", 10};
    security.policy = std::make_shared<const security::AuthPolicy>(
        security::AuthPolicy::load((dir_ / "policy.json").string()));
    audit_ = std::make_unique<store::AuditTrail>(db_, [](const std::string&) {});
    security.audit = audit_.get();
    runtime_ =
        std::make_unique<ServerRuntime>(ServerConfig{.address = "127.0.0.1:0",
                                                     .max_message_bytes = kStoreMessageBytes,
                                                     .services = {service_.get()},
                                                     .service_names = {"pnp.store.v1.StoreService"},
                                                     .security = security,
                                                     .log_name = "store"});
  }
  void TearDown() override {
    service_->stop_watches();
    runtime_->shutdown(std::chrono::milliseconds(100));
  }

  std::shared_ptr<grpc::Channel> channel(const std::string& who) const {
    ClientTlsFiles tls;
    tls.ca = (dir_ / "certs" / "ca.pem").string();
    tls.token_file = token_file(who);
    return dial_store("127.0.0.1:" + std::to_string(runtime_->port()), tls);
  }
  std::unique_ptr<RemoteStore> as(const std::string& who) const {
    return std::make_unique<RemoteStore>(channel(who), "store");
  }
  std::unique_ptr<v1::StoreService::Stub> stub(const std::string& who) const {
    return v1::StoreService::NewStub(channel(who));
  }

  // A run of `role` that `who` claimed as instance `instance`, with `blob` saved in it.
  store::CheckpointInfo trained(const std::string& who, const std::string& role,
                                const std::vector<std::uint8_t>& blob,
                                const std::string& instance = "worker-1") const {
    auto store = as(who);
    store->create_run(spec_of(role));
    const auto run = store->claim_next(role, instance, std::chrono::seconds(60));
    EXPECT_TRUE(run.has_value());
    return store->save_checkpoint(run->id, 1000, 0.9, blob, instance);
  }

  static inline fs::path dir_;
  std::string db_;
  std::unique_ptr<StreamLimits> limits_;
  std::unique_ptr<StoreServiceImpl> service_;
  std::unique_ptr<store::AuditTrail> audit_;
  std::unique_ptr<ServerRuntime> runtime_;
};

grpc::StatusCode promote_raw(v1::StoreService::Stub& stub, std::int64_t checkpoint_id,
                             const std::string& promoted_by, std::string* message = nullptr) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  v1::PromoteRequest request;
  request.add_checkpoint_ids(checkpoint_id);
  request.set_promoted_by(promoted_by);
  v1::PromotionsResponse response;
  const grpc::Status status = stub.Promote(&context, request, &response);
  if (message) *message = status.error_message();
  return status.error_code();
}

TEST_F(StoreIdentity, AForwardedAuditRecordNamesTheServerThatWroteItAndWhenItArrived) {
  const auto before = store::now_ms();
  // A trainer writes a backdated record of "ops" calling Resume.
  v1::AppendAuditRequest request;
  auto& forged = *request.add_records();
  forged.set_ts_ms(1000);  // 1970
  forged.set_service("robot-sim");
  forged.set_principal("ops");
  forged.set_rpc("/pnp.robot.v1.RobotControllerService/Resume");
  forged.set_request("{}");
  forged.set_code("OK");
  forged.set_recorded_by("robot-sim");  // the store's to set: ignored
  forged.set_received_ms(2000);
  {
    grpc::ClientContext context;
    v1::AppendAuditResponse response;
    ASSERT_TRUE(stub("approach")->AppendAudit(&context, request, &response).ok());
  }
  grpc::ClientContext context;
  v1::ReadAuditRequest read;
  read.set_limit(100);
  v1::ReadAuditResponse records;
  ASSERT_TRUE(stub("ops")->ReadAudit(&context, read, &records).ok());
  const v1::AuditEntry* found = nullptr;
  for (const auto& r : records.records())
    if (r.rpc() == "/pnp.robot.v1.RobotControllerService/Resume") found = &r;
  ASSERT_NE(found, nullptr);
  EXPECT_EQ(found->principal(), "ops");         // what the sender says
  EXPECT_EQ(found->recorded_by(), "approach");  // who the store authenticated
  EXPECT_GE(found->received_ms(), before);      // when it really arrived
  EXPECT_EQ(found->ts_ms(), 1000);
}

TEST_F(StoreIdentity, AServicePrincipalCannotPromoteOrImportAPromotedRun) {
  const auto checkpoint = trained("approach", "approach", checked_in("approach"));
  std::string message;
  EXPECT_EQ(promote_raw(*stub("approach"), checkpoint.id, "ops", &message),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(message.find("operator or delegate"), std::string::npos) << message;
  auto importer = as("approach");
  store::FinishedRun run{
      {"approach", "ddpg_her", "panda", "block", 0, "{}", "imported", std::nullopt},
      checked_in("approach")};
  code_of([&] { importer->import_finished(std::span(&run, 1), true); }, &message);
  EXPECT_NE(message.find("PERMISSION_DENIED"), std::string::npos) << message;
  EXPECT_NE(message.find("ImportFinished needs the operator class"), std::string::npos) << message;
  EXPECT_TRUE(as("ops")->promotions().empty());
}

TEST_F(StoreIdentity, APromotionIsRecordedAsTheOperatorOrTheOperatorViaTheServerActingForThem) {
  const auto first = trained("approach", "approach", checked_in("approach"));
  // pnp-inference carries out an operator's PromoteCheckpoint it authenticated.
  EXPECT_EQ(promote_raw(*stub("inference"), first.id, "ops"), grpc::StatusCode::OK);
  EXPECT_EQ(as("ops")->promoted("approach")->promoted_by, "ops via inference");
  // A delegate must say for whom; an operator promotes as itself, never as another.
  std::string message;
  EXPECT_EQ(promote_raw(*stub("inference"), first.id, "", &message),
            grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("promoted_by"), std::string::npos) << message;
  EXPECT_EQ(promote_raw(*stub("ops"), first.id, "someone-else", &message),
            grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("promoted_by"), std::string::npos) << message;
  EXPECT_EQ(promote_raw(*stub("ops"), first.id, ""), grpc::StatusCode::OK);
  EXPECT_EQ(as("ops")->promoted("approach")->promoted_by, "ops");
  // An operator's import, promoted: recorded as that operator.
  store::FinishedRun run{
      {"retract", "ddpg_her", "panda", "block", 0, "{}", "imported", std::nullopt},
      checked_in("retract")};
  as("ops")->import_finished(std::span(&run, 1), true);
  EXPECT_EQ(as("ops")->promoted("retract")->promoted_by, "ops");
}

TEST_F(StoreIdentity, ACheckpointThatAReplicaCouldNotServeIsNeverPromotedOrImported) {
  const auto garbage = trained("approach", "approach", {1, 2, 3});
  std::string message;
  EXPECT_EQ(promote_raw(*stub("ops"), garbage.id, "", &message), grpc::StatusCode::DATA_LOSS);
  EXPECT_NE(message.find("checkpoint_ids[0] " + std::to_string(garbage.id)), std::string::npos)
      << message;
  // A valid expert, but of another role than the run it is promoted for.
  const auto misplaced = trained("retract", "hlc", checked_in("retract"));
  EXPECT_EQ(promote_raw(*stub("ops"), misplaced.id, "", &message),
            grpc::StatusCode::INVALID_ARGUMENT);
  store::FinishedRun run{{"hlc", "a3c", "panda", "block", 0, "{}", "imported", std::nullopt},
                         checked_in("approach")};
  EXPECT_EQ(code_of([&] { as("ops")->import_finished(std::span(&run, 1), false); }, &message),
            ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("runs[0].checkpoint"), std::string::npos) << message;
  EXPECT_TRUE(as("ops")->promotions().empty());
  EXPECT_EQ(as("ops")->list_runs({}).size(), 2u);  // the two trained runs; nothing imported
  // The import's spool went with it.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(fs::path(db_).filename().string() + ".import-"),
              std::string::npos)
        << entry.path();
  }
}

TEST_F(StoreIdentity, ARunsOwnerIsTheAuthenticatedPrincipalAndNoOtherCanWriteAsIt) {
  const auto checkpoint = trained("approach", "approach", checked_in("approach"), "worker-1");
  auto owner = as("approach");
  const auto run = owner->get_run(checkpoint.run_id);
  EXPECT_EQ(run.owner, "approach/worker-1");
  // Another trainer reads the owner's name and writes with it: refused, nothing changes.
  auto other = as("retract");
  EXPECT_FALSE(other->renew_lease(run.id, "worker-1", std::chrono::seconds(60)));
  EXPECT_FALSE(other->renew_lease(run.id, run.owner, std::chrono::seconds(60)));
  EXPECT_EQ(code_of([&] {
              other->save_checkpoint(run.id, 2000, 1.0, checked_in("approach"), "worker-1");
            }),
            ErrorCode::kAborted);
  EXPECT_EQ(owner->checkpoints(run.id).size(), 1u);
  // Its rightful owner still holds it.
  EXPECT_TRUE(owner->renew_lease(run.id, "worker-1", std::chrono::seconds(60)));
}

TEST_F(StoreIdentity, ACreationKeyIsScopedToThePrincipalThatSentIt) {
  store::RunSpec spec = spec_of("approach");
  const auto mine = as("approach")->create_run(spec, "key-1");
  EXPECT_EQ(as("approach")->create_run(spec, "key-1").id, mine.id);
  // Another principal's identical key is its own: a run of its own, never the first's.
  EXPECT_NE(as("retract")->create_run(spec, "key-1").id, mine.id);
  EXPECT_EQ(as("ops")->list_runs({}).size(), 2u);
}

TEST_F(StoreIdentity, OnePrincipalCannotQueueMoreThanItsQuotaOfRuns) {
  store::RunSpec spec = spec_of("approach");
  auto trainer = as("approach");
  for (int k = 0; k < 3; ++k) trainer->create_run(spec);
  std::string message;
  code_of([&] { trainer->create_run(spec); }, &message);
  EXPECT_NE(message.find("RESOURCE_EXHAUSTED"), std::string::npos) << message;
  EXPECT_NE(message.find("--max-open-runs-per-principal 3"), std::string::npos) << message;
  as("retract")->create_run(spec);  // another principal's queue is its own
  // A checkpoint over the server's --max-checkpoint-mb is refused as it is announced.
  const auto run = trainer->claim_next("approach", "worker-1", std::chrono::seconds(60));
  ASSERT_TRUE(run.has_value());
  EXPECT_EQ(code_of([&] {
              trainer->save_checkpoint(run->id, 100, 0.5,
                                       std::vector<std::uint8_t>((4 << 20) + 1, 1), "worker-1");
            }),
            ErrorCode::kInvalidArgument);
}

// One open WatchPromotions: `admitted` if its first message arrived.
struct Watch {
  explicit Watch(v1::StoreService::Stub& stub) {
    reader = stub.WatchPromotions(&context, {});
    v1::PromotionsResponse first;
    admitted = reader->Read(&first);
    if (!admitted) status = reader->Finish();
  }
  ~Watch() {
    context.TryCancel();
    if (admitted) reader->Finish();
  }
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientReader<v1::PromotionsResponse>> reader;
  bool admitted = false;
  grpc::Status status;
};

TEST_F(StoreIdentity, AReaderCannotTakeTheWatchSlotsAnotherPrincipalNeeds) {
  auto dashboard = stub("dashboard");
  const Watch first(*dashboard);
  EXPECT_TRUE(first.admitted);
  const Watch second(*dashboard);
  ASSERT_FALSE(second.admitted);
  EXPECT_EQ(second.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(second.status.error_message().find("--max-streams-per-principal"), std::string::npos)
      << second.status.error_message();
  // The inference replica's watch still finds its slot.
  auto inference = stub("inference");
  const Watch replica(*inference);
  EXPECT_TRUE(replica.admitted) << replica.status.error_message();
}

// An upload held open, as a slow or stalled trainer would.
struct OpenUpload {
  OpenUpload(v1::StoreService::Stub& stub, std::int64_t run_id) {
    writer = stub.SaveCheckpoint(&context, &response);
    v1::SaveCheckpointRequest header;
    header.mutable_header()->set_run_id(run_id);
    header.mutable_header()->set_size_bytes(3 << 20);
    header.mutable_header()->set_checksum("0123456789abcdef");
    header.mutable_header()->mutable_evaluated()->set_env_steps(1);
    writer->Write(header);
  }
  grpc::Status finish() {
    writer->WritesDone();
    return writer->Finish();
  }
  grpc::ClientContext context;
  v1::CheckpointInfo response;
  std::unique_ptr<grpc::ClientWriter<v1::SaveCheckpointRequest>> writer;
};

TEST_F(StoreIdentity, CheckpointTransfersAreCountedAgainstTheirPrincipalsStreams) {
  const auto first = trained("approach", "approach", checked_in("approach"));
  OpenUpload held(*stub("approach"), first.run_id);
  // The same principal's next transfer finds its one stream taken...
  OpenUpload second(*stub("approach"), first.run_id);
  const grpc::Status refused = second.finish();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(refused.error_message().find("SaveCheckpoint"), std::string::npos)
      << refused.error_message();
  EXPECT_NE(refused.error_message().find("--max-streams-per-principal"), std::string::npos)
      << refused.error_message();
  // ...while another trainer saves and loads as usual.
  const auto other = trained("retract", "retract", checked_in("retract"));
  EXPECT_EQ(as("retract")->load_checkpoint(other.id).blob, checked_in("retract"));
  held.context.TryCancel();
  held.finish();
}

TEST_F(StoreIdentity, ATrainerBoundToItsRoleCannotCreateClaimOrCountAnotherRolesRuns) {
  store::RunSpec spec = spec_of("retract");
  auto approach = as("approach");
  std::string message;
  EXPECT_EQ(code_of([&] { approach->create_run(spec); }, &message), ErrorCode::kPermissionDenied);
  EXPECT_NE(message.find("spec.role: principal \"approach\" acts for the roles approach only"),
            std::string::npos)
      << message;
  const auto queued = as("retract")->create_run(spec);
  EXPECT_EQ(code_of([&] { approach->claim_next("retract", "worker-1", std::chrono::seconds(60)); },
                    &message),
            ErrorCode::kPermissionDenied);
  EXPECT_NE(message.find("not \"retract\""), std::string::npos) << message;
  EXPECT_EQ(code_of([&] { approach->count_claimable("retract", "worker-1"); }),
            ErrorCode::kPermissionDenied);
  // Its own queue as before; the retract run waits for the retract trainer.
  spec.role = "approach";
  approach->create_run(spec);
  EXPECT_EQ(approach->claim_next("approach", "worker-1", std::chrono::seconds(60))->spec.role,
            "approach");
  EXPECT_EQ(as("retract")->claim_next("retract", "worker-1", std::chrono::seconds(60))->id,
            queued.id);
}

}  // namespace
}  // namespace pnp::services
