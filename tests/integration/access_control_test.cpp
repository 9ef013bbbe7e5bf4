// Integration: the inference and training servers started with TLS and an authorization
// policy (certificates, tokens and policy from scripts/make-dev-certs), called by plain
// gRPC clients with standard credentials and by the real pnpctl: who may do what, and
// the audit trail that records it.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tests/integration/child_process.h"

namespace {

using pnp::integration::ChildProcess;
using pnp::integration::loopback;
using pnp::integration::TempDir;
using namespace std::chrono_literals;
namespace pv1 = pnp::policy::v1;
namespace tv1 = pnp::train::v1;

std::string first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

class SecuredServers : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string make = std::string(PNP_SOURCE_DIR) + "/scripts/make-dev-certs --out " +
                             dir_.file("certs") + " 2>/dev/null";
    ASSERT_EQ(std::system(make.c_str()), 0) << make;
    {
      pnp::store::RunStore store(db_);
      hierarchy_ = pnp::store::import_hierarchy(store, PNP_SOURCE_DIR "/tests/data/panda_block",
                                                "panda", "block");
    }
    const std::vector<std::string> tls = {"--tls-cert",    cert("server.pem"),
                                          "--tls-key",     cert("server.key"),
                                          "--auth-policy", cert("policy.json")};
    std::vector<std::string> inference = {PNP_BIN_DIR "/pnp-inference-server", "--address",
                                          "127.0.0.1:0", "--db", db_};
    inference.insert(inference.end(), tls.begin(), tls.end());
    inference_ = std::make_unique<ChildProcess>("inference", inference, dir_.path());
    std::vector<std::string> train = {PNP_BIN_DIR "/pnp-train-server",
                                      "--role",
                                      "approach",
                                      "--address",
                                      "127.0.0.1:0",
                                      "--threads",
                                      "1",
                                      "--db",
                                      db_};
    train.insert(train.end(), tls.begin(), tls.end());
    train_ = std::make_unique<ChildProcess>("train", train, dir_.path());
    ASSERT_GT(inference_->port(), 0) << inference_->diagnostics();
    ASSERT_GT(train_->port(), 0) << train_->diagnostics();
  }

  std::string cert(const std::string& name) const { return dir_.file("certs/" + name); }

  // A channel over TLS (trusting the development CA) sending `who`'s token, if any.
  std::shared_ptr<grpc::Channel> tls_channel(int port, const std::string& who) const {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = pnp::integration::read_file(cert("ca.pem"));
    auto credentials = grpc::SslCredentials(ssl);
    if (!who.empty()) {
      credentials = grpc::CompositeChannelCredentials(
          credentials, grpc::AccessTokenCredentials(first_line(cert(who + ".token"))));
    }
    return grpc::CreateChannel(loopback(port), credentials);
  }

  static std::unique_ptr<grpc::ClientContext> context() {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + 10s);
    return c;
  }

  grpc::Status promote(const std::shared_ptr<grpc::Channel>& channel) const {
    pv1::PromoteCheckpointRequest request;
    for (const auto id : hierarchy_) request.add_checkpoint_ids(id);
    pv1::PromoteCheckpointResponse response;
    return pv1::PolicyService::NewStub(channel)->PromoteCheckpoint(context().get(), request,
                                                                   &response);
  }

  // pnpctl over TLS as `who`, run to its end: exit code, stdout and stderr.
  struct Cli {
    int code = -1;
    std::string out, err;
  };
  Cli pnpctl(const std::string& who, std::vector<std::string> args) {
    std::vector<std::string> full = {PNP_BIN_DIR "/pnpctl",
                                     "--inference",
                                     loopback(inference_->port()),
                                     "--approach",
                                     loopback(train_->port()),
                                     "--tls-ca",
                                     cert("ca.pem")};
    if (!who.empty()) full.insert(full.end(), {"--token-file", cert(who + ".token")});
    full.insert(full.end(), args.begin(), args.end());
    ChildProcess cli("pnpctl-" + std::to_string(++calls_), full, dir_.path());
    const auto status = cli.wait(120s);
    if (!status) cli.kill();
    return {status && status->exited ? status->code : -1, cli.stdout_text(), cli.stderr_text()};
  }

  TempDir dir_{"secured_servers"};
  std::string db_ = dir_.file("pnp.db");
  std::vector<std::int64_t> hierarchy_;
  std::unique_ptr<ChildProcess> inference_, train_;
  int calls_ = 0;
};

TEST_F(SecuredServers, APlaintextClientFails) {
  auto plaintext =
      grpc::CreateChannel(loopback(inference_->port()), grpc::InsecureChannelCredentials());
  pv1::GetServingStatusResponse status;
  EXPECT_EQ(pv1::PolicyService::NewStub(plaintext)
                ->GetServingStatus(context().get(), {}, &status)
                .error_code(),
            grpc::StatusCode::UNAVAILABLE);
}

// pnpctl without --tls-ca at a TLS server says what to pass, without gRPC's own log lines
// (it said "UNAVAILABLE ... Socket closed" after an "E1206 ..." line).
TEST_F(SecuredServers, APlaintextPnpctlIsToldToDialWithTls) {
  ChildProcess cli(
      "pnpctl-plaintext",
      {PNP_BIN_DIR "/pnpctl", "--inference", loopback(inference_->port()), "promote", "1"},
      dir_.path());
  const auto status = cli.wait(60s);
  ASSERT_TRUE(status && status->exited) << cli.stderr_text();
  EXPECT_EQ(status->code, 1);
  EXPECT_NE(cli.stderr_text().find("if it serves TLS, dial it with --tls-ca"), std::string::npos)
      << cli.stderr_text();
  EXPECT_EQ(cli.stderr_text().find("E1"), std::string::npos) << cli.stderr_text();
}

TEST_F(SecuredServers, TlsWithoutCredentialsIsUnauthenticatedOnPromoteCheckpoint) {
  const grpc::Status status = promote(tls_channel(inference_->port(), ""));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << status.error_message();
  EXPECT_NE(status.error_message().find("PromoteCheckpoint"), std::string::npos);
}

TEST_F(SecuredServers, AReaderMayReadButNotPromoteOrTrain) {
  auto reader = tls_channel(inference_->port(), "reader");
  pv1::GetServingStatusResponse status;
  EXPECT_TRUE(
      pv1::PolicyService::NewStub(reader)->GetServingStatus(context().get(), {}, &status).ok());
  const grpc::Status denied = promote(reader);
  EXPECT_EQ(denied.error_code(), grpc::StatusCode::PERMISSION_DENIED) << denied.error_message();
  EXPECT_NE(denied.error_message().find("PromoteCheckpoint needs the operator class"),
            std::string::npos)
      << denied.error_message();
  EXPECT_EQ(denied.error_message().find(first_line(cert("reader.token"))), std::string::npos);
  // Through pnpctl, on the training service: listing is reading, training is operating.
  const Cli runs = pnpctl("reader", {"runs", "--role", "approach"});
  EXPECT_EQ(runs.code, 0) << runs.err;
  const Cli train = pnpctl("reader", {"train", "--role", "approach", "--max-steps", "1000"});
  EXPECT_NE(train.code, 0);
  EXPECT_NE(train.err.find("PERMISSION_DENIED: /pnp.train.v1.TrainingService/CreateTrainingRun "
                           "needs the operator class"),
            std::string::npos)
      << train.err;
  // The refused promotion changed nothing: the roles are still those the import promoted,
  // by no principal.
  pv1::GetServingStatusResponse after;
  ASSERT_TRUE(
      pv1::PolicyService::NewStub(reader)->GetServingStatus(context().get(), {}, &after).ok());
  ASSERT_EQ(after.roles_size(), 4);
  for (const auto& role : after.roles()) EXPECT_EQ(role.promoted_by(), "");
}

TEST_F(SecuredServers, AnOperatorPromotesAndTheAuditTrailSaysWho) {
  const Cli promoted =
      pnpctl("ops", {"promote", std::to_string(hierarchy_[0]), std::to_string(hierarchy_[1]),
                     std::to_string(hierarchy_[2]), std::to_string(hierarchy_[3])});
  ASSERT_EQ(promoted.code, 0) << promoted.err;
  pv1::GetServingStatusResponse status;
  ASSERT_TRUE(pv1::PolicyService::NewStub(tls_channel(inference_->port(), "reader"))
                  ->GetServingStatus(context().get(), {}, &status)
                  .ok());
  ASSERT_EQ(status.roles_size(), 4);
  for (const auto& role : status.roles()) EXPECT_EQ(role.promoted_by(), "ops");
  // A refused attempt is audited too.
  EXPECT_EQ(promote(tls_channel(inference_->port(), "reader")).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  // The trail is written in the background: ask until both calls are there.
  Cli audit;
  const bool listed = pnp::integration::wait_until(
      [&] {
        audit = pnpctl("", {"audit", "--db", db_, "--json"});
        return audit.out.find("PERMISSION_DENIED") != std::string::npos;
      },
      30s, 200ms);
  ASSERT_TRUE(listed) << audit.out << audit.err;
  EXPECT_NE(audit.out.find(R"("principal":"ops")"), std::string::npos) << audit.out;
  EXPECT_NE(audit.out.find(R"("rpc":"/pnp.policy.v1.PolicyService/PromoteCheckpoint")"),
            std::string::npos);
  EXPECT_NE(audit.out.find(R"("code":"OK")"), std::string::npos);
  EXPECT_NE(audit.out.find(std::to_string(hierarchy_[0])), std::string::npos)
      << "the request's checkpoint ids are recorded";
  // The table form, as an operator reads it.
  const Cli table = pnpctl("", {"audit", "--db", db_, "--since", "1h"});
  EXPECT_NE(table.out.find("PolicyService/PromoteCheckpoint"), std::string::npos) << table.out;
  // Requests are cut so that a row fits a wide terminal (they made 300-character rows).
  std::istringstream rows(table.out);
  for (std::string row; std::getline(rows, row);) EXPECT_LE(row.size(), 200u) << row;
  // No token ever reaches a log.
  for (const char* who : {"ops", "reader"}) {
    const std::string token = first_line(cert(std::string(who) + ".token"));
    EXPECT_EQ(inference_->stderr_text().find(token), std::string::npos) << who;
    EXPECT_EQ(audit.out.find(token), std::string::npos) << who;
  }
}

}  // namespace
