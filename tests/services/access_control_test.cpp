// Transport security and authorization in process: a real server (ServerRuntime with TLS,
// mutual TLS, an auth policy and an audit trail) on a free loopback port, called through
// real stubs over real TLS, with certificates and tokens made by scripts/make-dev-certs.
#include "services/common/access_control.h"

#include <google/protobuf/descriptor.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "common/error.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "pnp/store/v1/store_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "security/rpc_access.h"
#include "services/common/server_runtime.h"
#include "services/common/transport_security.h"
#include "store/audit_trail.h"

namespace pnp::services {
namespace {

namespace fs = std::filesystem;
namespace rv1 = robot::v1;

// ---------------------------------------------------------------------------------------
// The table: every RPC of every .proto service has a class, and nothing else is in it.

std::vector<std::string> proto_files() {
  std::vector<std::string> out;
  const fs::path root = fs::path(PNP_SOURCE_DIR) / "proto";
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.path().extension() == ".proto")
      out.push_back(fs::relative(entry.path(), root).generic_string());
  return out;
}

TEST(RpcAccessTable, EveryRpcOfEveryServiceHasAClass) {
  // Naming one message of each file links its descriptor in (pnp_proto is a static
  // library); a new .proto fails below until it is named here too.
  for (const auto* linked :
       {grpc::health::v1::HealthCheckRequest::descriptor(), common::v1::Vector3::descriptor(),
        policy::v1::PredictRequest::descriptor(), robot::v1::StopRequest::descriptor(),
        sim::v1::StepRequest::descriptor(), train::v1::TrainingRun::descriptor(),
        pnp::store::v1::GetRunRequest::descriptor()})
    ASSERT_NE(linked, nullptr);
  const auto* pool = google::protobuf::DescriptorPool::generated_pool();
  std::set<std::string> declared;
  const auto files = proto_files();
  ASSERT_GE(files.size(), 5u);
  for (const std::string& name : files) {
    const auto* file = pool->FindFileByName(name);
    ASSERT_NE(file, nullptr) << name << ": not linked; name one of its messages above";
    for (int s = 0; s < file->service_count(); ++s) {
      const auto* service = file->service(s);
      for (int m = 0; m < service->method_count(); ++m) {
        const std::string path = "/" + service->full_name() + "/" + service->method(m)->name();
        declared.insert(path);
        EXPECT_NE(security::find_rpc_access(path), nullptr)
            << path << " has no access class in core/security/rpc_access.cpp";
      }
    }
  }
  EXPECT_GE(declared.size(), 25u);
  // No stale entries: each row names a declared RPC or the reflection every server adds.
  for (const auto& row : security::rpc_access_table()) {
    const std::string path(row.path);
    if (path.starts_with("/grpc.reflection.")) continue;
    EXPECT_TRUE(declared.contains(path)) << path << " is in the table but in no .proto";
  }
}

TEST(RpcAccessTable, OperatorAndRobotCallsAndStopAreAudited) {
  for (const auto& row : security::rpc_access_table()) {
    const auto& c = row.requirement.access_class;
    const auto& alternative = row.requirement.or_class;
    const bool moves_or_operates = !c || *c == security::AccessClass::kOperator ||
                                   *c == security::AccessClass::kRobot ||
                                   alternative == security::AccessClass::kOperator;
    EXPECT_EQ(row.audited, moves_or_operates) << row.path;
  }
}

// ---------------------------------------------------------------------------------------
// A controller with just enough behaviour to observe what reaches a handler.

class RecordingController final : public rv1::RobotControllerService::Service {
 public:
  grpc::Status AcquireLease(grpc::ServerContext* context, const rv1::AcquireLeaseRequest*,
                            rv1::AcquireLeaseResponse* response) override {
    seen(*context);
    response->set_lease_id("lease-1");
    return grpc::Status::OK;
  }
  grpc::Status ReleaseLease(grpc::ServerContext* context, const rv1::ReleaseLeaseRequest*,
                            rv1::ReleaseLeaseResponse*) override {
    seen(*context);
    return grpc::Status::OK;
  }
  grpc::Status Stop(grpc::ServerContext* context, const rv1::StopRequest*,
                    rv1::StopResponse*) override {
    seen(*context);
    return grpc::Status::OK;
  }
  grpc::Status GetState(grpc::ServerContext* context, const rv1::GetStateRequest*,
                        rv1::GetStateResponse*) override {
    seen(*context);
    return grpc::Status::OK;
  }

  std::string last_principal() const {
    std::lock_guard lock(mutex_);
    return principal_;
  }
  bool saw_authorization_header() const {
    std::lock_guard lock(mutex_);
    return saw_authorization_;
  }

 private:
  void seen(const grpc::ServerContext& context) {
    std::lock_guard lock(mutex_);
    principal_ = principal_of(context);
    saw_authorization_ = saw_authorization_ || context.client_metadata().find("authorization") !=
                                                   context.client_metadata().end();
  }
  mutable std::mutex mutex_;
  std::string principal_;
  bool saw_authorization_ = false;
};

class AccessControl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("pnp_access_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    for (const char* ca : {"a", "b"}) {
      const std::string command = std::string(PNP_SOURCE_DIR) + "/scripts/make-dev-certs --out " +
                                  (dir_ / ca).string() + " 2>/dev/null";
      ASSERT_EQ(std::system(command.c_str()), 0) << command;
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string file(const char* ca, const std::string& name) {
    return (dir_ / ca / name).string();
  }

  // Starts the server: TLS from CA "a", optionally requiring client certificates, with
  // the generated policy and an audit trail.
  void start(bool mutual_tls, bool with_policy = true, unsigned reload_s = 10) {
    security_.tls = {file("a", "server.pem"), file("a", "server.key"),
                     mutual_tls ? file("a", "ca.pem") : "", reload_s};
    if (with_policy)
      security_.policy = std::make_shared<const security::AuthPolicy>(
          security::AuthPolicy::load(file("a", "policy.json")));
    audit_ = std::make_unique<store::AuditTrail>(audit_path(), [](const std::string&) {});
    security_.audit = audit_.get();
    runtime_ = std::make_unique<ServerRuntime>(
        ServerConfig{.address = "127.0.0.1:0",
                     .services = {&controller_},
                     .service_names = {"pnp.robot.v1.RobotControllerService"},
                     .security = security_,
                     .log_name = "access-test"});
  }
  void TearDown() override {
    if (runtime_) runtime_->shutdown(std::chrono::milliseconds(100));
  }

  std::string address() const { return "127.0.0.1:" + std::to_string(runtime_->port()); }

  // A client of CA `ca` as principal `who` ("" for none) by token and/or certificate.
  std::unique_ptr<rv1::RobotControllerService::Stub> client(const char* ca, const std::string& who,
                                                            bool by_token, bool by_cert) {
    ClientTlsFiles tls;
    tls.ca = file(ca, "ca.pem");
    if (by_cert) tls.cert = file(ca, who + ".pem"), tls.key = file(ca, who + ".key");
    if (by_token) tls.token_file = file(ca, who + ".token");
    return rv1::RobotControllerService::NewStub(dial(address(), tls));
  }

  static grpc::Status stop(rv1::RobotControllerService::Stub& stub) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    rv1::StopRequest request;
    request.set_reason("test");
    rv1::StopResponse response;
    return stub.Stop(&context, request, &response);
  }
  static grpc::Status acquire(rv1::RobotControllerService::Stub& stub) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    rv1::AcquireLeaseRequest request;
    rv1::AcquireLeaseResponse response;
    return stub.AcquireLease(&context, request, &response);
  }
  static grpc::Status state(rv1::RobotControllerService::Stub& stub) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    rv1::GetStateRequest request;
    rv1::GetStateResponse response;
    return stub.GetState(&context, request, &response);
  }

  std::vector<store::AuditRecord> audit_records() {
    audit_->flush();
    return store::read_audit(audit_path(), 0, 1000);
  }
  // One store per test: each sees only its own calls.
  static std::string audit_path() {
    return (dir_ /
            (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".db"))
        .string();
  }

  static inline fs::path dir_;
  RecordingController controller_;
  ServerSecurity security_;
  std::unique_ptr<store::AuditTrail> audit_;
  std::unique_ptr<ServerRuntime> runtime_;
};

TEST_F(AccessControl, APlaintextClientCannotTalkToATlsServer) {
  start(/*mutual_tls=*/false);
  auto stub = rv1::RobotControllerService::NewStub(
      grpc::CreateChannel(address(), grpc::InsecureChannelCredentials()));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(3));
  rv1::GetStateResponse response;
  EXPECT_EQ(stub->GetState(&context, rv1::GetStateRequest(), &response).error_code(),
            grpc::StatusCode::UNAVAILABLE);
}

TEST_F(AccessControl, AClientThatTrustsAnotherCaIsRefused) {
  start(/*mutual_tls=*/false);
  EXPECT_EQ(state(*client("b", "reader", true, false)).error_code(), grpc::StatusCode::UNAVAILABLE);
}

TEST_F(AccessControl, NoCredentialsIsUnauthenticatedNamingTheRpc) {
  start(/*mutual_tls=*/false);
  const grpc::Status status = stop(*client("a", "", false, false));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(status.error_message().find("/pnp.robot.v1.RobotControllerService/Stop"),
            std::string::npos);
  const auto records = audit_records();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].code, "UNAUTHENTICATED");
  EXPECT_EQ(records[0].principal, "");
}

TEST_F(AccessControl, AReaderTokenMayReadAndStopButNotTakeALease) {
  start(/*mutual_tls=*/false);
  auto reader = client("a", "reader", /*by_token=*/true, /*by_cert=*/false);
  EXPECT_TRUE(state(*reader).ok());
  EXPECT_EQ(controller_.last_principal(), "reader");
  const grpc::Status lease = acquire(*reader);
  EXPECT_EQ(lease.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(lease.error_message().find("AcquireLease needs the robot class"), std::string::npos);
  const std::string token = [] {
    std::ifstream in(file("a", "reader.token"));
    std::string t;
    std::getline(in, t);
    return t;
  }();
  EXPECT_EQ(lease.error_message().find(token), std::string::npos);
  EXPECT_TRUE(stop(*reader).ok());
  // The token is consumed by the access check: no handler ever sees it.
  EXPECT_FALSE(controller_.saw_authorization_header());
  const auto records = audit_records();
  ASSERT_EQ(records.size(), 2u);  // the refused lease and the stop; reads are not audited
  EXPECT_EQ(records[0].rpc, "/pnp.robot.v1.RobotControllerService/AcquireLease");
  EXPECT_EQ(records[0].code, "PERMISSION_DENIED");
  EXPECT_EQ(records[1].rpc, "/pnp.robot.v1.RobotControllerService/Stop");
  EXPECT_EQ(records[1].principal, "reader");
  EXPECT_EQ(records[1].code, "OK");
  EXPECT_NE(records[1].request.find("\"reason\":\"test\""), std::string::npos);
  EXPECT_NE(records[1].peer.find("127.0.0.1"), std::string::npos);
}

// A lease id is the capability to drive the arm: the audit records the call, never the id.
TEST_F(AccessControl, TheAuditNeverRecordsALeaseId) {
  start(/*mutual_tls=*/true);
  auto gateway = client("a", "gateway", /*by_token=*/false, /*by_cert=*/true);
  ASSERT_TRUE(acquire(*gateway).ok());
  grpc::ClientContext context;
  rv1::ReleaseLeaseRequest request;
  request.set_lease_id("lease-1");
  rv1::ReleaseLeaseResponse response;
  ASSERT_TRUE(gateway->ReleaseLease(&context, request, &response).ok());
  const auto records = audit_records();
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[1].rpc, "/pnp.robot.v1.RobotControllerService/ReleaseLease");
  EXPECT_EQ(records[1].principal, "gateway");
  EXPECT_EQ(records[1].request, "{\"lease_id\":\"[redacted]\"}");
  for (const auto& r : records) EXPECT_EQ(r.request.find("lease-1"), std::string::npos);
}

TEST_F(AccessControl, AnUnknownTokenIsUnauthenticatedEvenForReads) {
  start(/*mutual_tls=*/false);
  // CA b's tokens were never put in CA a's policy.
  ClientTlsFiles tls;
  tls.ca = file("a", "ca.pem");
  tls.token_file = file("b", "ops.token");
  auto stub = rv1::RobotControllerService::NewStub(dial(address(), tls));
  EXPECT_EQ(state(*stub).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(AccessControl, MutualTlsNamesThePrincipalByItsCertificate) {
  start(/*mutual_tls=*/true);
  auto gateway = client("a", "gateway", /*by_token=*/false, /*by_cert=*/true);
  EXPECT_TRUE(acquire(*gateway).ok());
  EXPECT_EQ(controller_.last_principal(), "gateway");
  auto ops = client("a", "ops", false, true);
  EXPECT_EQ(acquire(*ops).error_code(), grpc::StatusCode::PERMISSION_DENIED);
}

TEST_F(AccessControl, MutualTlsRefusesAClientWithoutACertificateOrWithAStrangersOne) {
  start(/*mutual_tls=*/true);
  EXPECT_EQ(state(*client("a", "ops", /*by_token=*/true, /*by_cert=*/false)).error_code(),
            grpc::StatusCode::UNAVAILABLE);
  // A certificate from another CA, trusting the right server CA.
  ClientTlsFiles tls;
  tls.ca = file("a", "ca.pem");
  tls.cert = file("b", "gateway.pem");
  tls.key = file("b", "gateway.key");
  auto stub = rv1::RobotControllerService::NewStub(dial(address(), tls));
  EXPECT_EQ(state(*stub).error_code(), grpc::StatusCode::UNAVAILABLE);
}

TEST_F(AccessControl, WithoutAPolicyTlsAloneLetsEveryClientCall) {
  start(/*mutual_tls=*/false, /*with_policy=*/false);
  EXPECT_TRUE(acquire(*client("a", "", false, false)).ok());
  EXPECT_EQ(controller_.last_principal(), "");
  const auto records = audit_records();
  ASSERT_EQ(records.size(), 1u);  // still audited, without a principal
  EXPECT_EQ(records[0].code, "OK");
}

TEST_F(AccessControl, HealthAndReflectionNeedTheReaderClass) {
  start(/*mutual_tls=*/false);
  auto health = [&](const std::string& who) {
    ClientTlsFiles tls;
    tls.ca = file("a", "ca.pem");
    if (!who.empty()) tls.token_file = file("a", who + ".token");
    auto stub = grpc::health::v1::Health::NewStub(dial(address(), tls));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    grpc::health::v1::HealthCheckResponse response;
    return stub->Check(&context, grpc::health::v1::HealthCheckRequest(), &response).error_code();
  };
  EXPECT_EQ(health(""), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(health("reader"), grpc::StatusCode::OK);
}

// Rotation: the server's certificate file is replaced by one from another CA; without a
// restart the server presents the new one (clients of the new CA connect, of the old do
// not).
TEST_F(AccessControl, ARotatedServerCertificateIsServedWithoutARestart) {
  const fs::path live = dir_ / "live";
  fs::create_directories(live);
  fs::copy_file(file("a", "server.pem"), live / "server.pem", fs::copy_options::overwrite_existing);
  fs::copy_file(file("a", "server.key"), live / "server.key", fs::copy_options::overwrite_existing);
  security_.tls = {(live / "server.pem").string(), (live / "server.key").string(), "", 1};
  runtime_ = std::make_unique<ServerRuntime>(
      ServerConfig{.address = "127.0.0.1:0", .services = {&controller_}, .security = security_});
  EXPECT_TRUE(state(*client("a", "", false, false)).ok());
  // Renamed into place, key first: the watcher never pairs a new certificate with an old
  // key for long, and never reads a half-written file.
  fs::copy_file(file("b", "server.key"), live / "server.key.new");
  fs::copy_file(file("b", "server.pem"), live / "server.pem.new");
  fs::rename(live / "server.key.new", live / "server.key");
  fs::rename(live / "server.pem.new", live / "server.pem");
  bool rotated = false;
  for (int attempt = 0; attempt < 60 && !rotated; ++attempt) {
    // A fresh channel each time: a connected one keeps its handshake.
    rotated = state(*client("b", "", false, false)).ok();
    if (!rotated) std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  EXPECT_TRUE(rotated) << "the server never presented the rotated certificate";
  EXPECT_EQ(state(*client("a", "", false, false)).error_code(), grpc::StatusCode::UNAVAILABLE);
}

TEST(ServerExposure, PlaintextBeyondLoopbackIsRefusedUnlessInsecure) {
  RecordingController controller;
  auto refused = [&](ServerConfig config) {
    try {
      ServerRuntime runtime(config);
      runtime.shutdown(std::chrono::milliseconds(0));
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refused({.address = "0.0.0.0:0", .services = {&controller}}).find("--insecure"),
            std::string::npos);
  EXPECT_NE(refused({.address = "[::]:0", .services = {&controller}}).find("--address"),
            std::string::npos);
  MetricsRegistry metrics;
  EXPECT_NE(refused({.address = "127.0.0.1:0",
                     .services = {&controller},
                     .metrics = &metrics,
                     .metrics_address = "0.0.0.0:0"})
                .find("--metrics-address"),
            std::string::npos);
  ServerSecurity with_policy;
  with_policy.policy = std::make_shared<const security::AuthPolicy>(security::AuthPolicy::parse(
      R"({"principals": [{"name": "a", "cert_cn": "a", "classes": ["reader"]}]})", "p"));
  EXPECT_NE(refused({.address = "127.0.0.1:0", .services = {&controller}, .security = with_policy})
                .find("--auth-policy needs TLS"),
            std::string::npos);
  ServerSecurity public_metrics;
  public_metrics.public_metrics = true;
  EXPECT_EQ(refused({.address = "127.0.0.1:0",
                     .services = {&controller},
                     .metrics = &metrics,
                     .metrics_address = "0.0.0.0:0",
                     .security = public_metrics}),
            "");
  ServerSecurity insecure;
  insecure.insecure = true;
  EXPECT_EQ(refused({.address = "0.0.0.0:0", .services = {&controller}, .security = insecure}), "");
}

// TLS encrypts but does not say who calls: beyond loopback a server also needs client
// certificates or tokens. (check_exposure reads no files: the names stand for them.)
TEST(ServerExposure, TlsWithoutClientAuthenticationBeyondLoopbackIsRefused) {
  ServerSecurity tls_only;
  tls_only.tls.cert = "server.pem";
  tls_only.tls.key = "server.key";
  try {
    check_exposure("0.0.0.0:50051", "", tls_only);
    FAIL() << "TLS without client authentication was allowed beyond loopback";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("--tls-client-ca or --auth-policy"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(check_exposure("127.0.0.1:50051", "", tls_only)) << "loopback: the machine's";
  ServerSecurity mutual = tls_only;
  mutual.tls.client_ca = "ca.pem";
  EXPECT_NO_THROW(check_exposure("0.0.0.0:50051", "", mutual));
  ServerSecurity tokens = tls_only;
  tokens.policy = std::make_shared<const security::AuthPolicy>(security::AuthPolicy::parse(
      R"({"principals": [{"name": "a", "cert_cn": "a", "classes": ["reader"]}]})", "p"));
  EXPECT_NO_THROW(check_exposure("0.0.0.0:50051", "", tokens));
  ServerSecurity insecure = tls_only;
  insecure.insecure = true;
  EXPECT_NO_THROW(check_exposure("0.0.0.0:50051", "", insecure));
}

TEST(ClientTransport, ATokenIsNeverSentOverPlaintext) {
  ClientTlsFiles tls;
  tls.token_file = "/dev/null";
  try {
    dial("127.0.0.1:1", tls);
    FAIL() << "dialled plaintext with a token";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("--token-file needs TLS"), std::string::npos);
  }
}

TEST(ClientTransport, HalfACertificatePairIsRefusedNamingTheFlag) {
  ClientTlsFiles tls;
  tls.ca = "/dev/null";
  tls.cert = "/dev/null";
  try {
    validate(tls);
    FAIL() << "accepted --tls-cert without --tls-key";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("--tls-key"), std::string::npos);
  }
}

}  // namespace
}  // namespace pnp::services
