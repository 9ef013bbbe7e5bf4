// The authorization policy: what it accepts, what it refuses (naming the field), and who
// each presented credential is and may do.
#include "security/auth_policy.h"

#include <gtest/gtest.h>

#include "security/rpc_access.h"
#include "security/sha256.h"
#include "support/refusal.h"

namespace pnp::security {
namespace {

using pnp::testing::refusal;
using Outcome = AccessDecision::Outcome;

const std::string kOpsToken = "ops-secret-token";
const std::string kReaderToken = "reader-secret-token";

AuthPolicy example_policy() {
  return AuthPolicy::parse(R"({"principals": [
      {"name": "ops", "token_sha256": ")" +
                               sha256_hex(kOpsToken) + R"(",
       "classes": ["reader", "operator"]},
      {"name": "dashboard", "token_sha256": ")" +
                               sha256_hex(kReaderToken) + R"(",
       "classes": ["reader"]},
      {"name": "gateway", "cert_cn": "gateway", "classes": ["agent", "robot"]},
      {"name": "trainer", "cert_san": "trainer.pnp.internal", "classes": ["agent"]}]})",
                           "policy.json");
}

PresentedCredentials token(const std::string& t) {
  PresentedCredentials c;
  c.bearer_token = t;
  return c;
}

PresentedCredentials certificate(const std::string& cn, std::vector<std::string> sans = {}) {
  PresentedCredentials c;
  c.cert_common_name = cn;
  c.cert_sans = std::move(sans);
  return c;
}

AccessDecision decide(const PresentedCredentials& who, const std::string& rpc) {
  const RpcAccess* access = find_rpc_access(rpc);
  return decide_access(example_policy(), who, rpc,
                       access ? std::optional(access->requirement) : std::nullopt);
}

constexpr const char* kPromote = "/pnp.policy.v1.PolicyService/PromoteCheckpoint";
constexpr const char* kStatus = "/pnp.policy.v1.PolicyService/GetServingStatus";
constexpr const char* kStop = "/pnp.robot.v1.RobotControllerService/Stop";
constexpr const char* kStream = "/pnp.robot.v1.RobotControllerService/StreamPoseTargets";

TEST(AuthPolicy, RecognisesPrincipalsByTokenCertificateSubjectOrSan) {
  const AuthPolicy policy = example_policy();
  ASSERT_EQ(policy.principals().size(), 4u);
  ASSERT_NE(policy.by_token(kOpsToken), nullptr);
  EXPECT_EQ(policy.by_token(kOpsToken)->name, "ops");
  EXPECT_EQ(policy.by_token("ops-secret-tokeN"), nullptr);
  EXPECT_EQ(policy.by_token(""), nullptr);
  const std::vector<std::string> none, san = {"trainer.pnp.internal"};
  ASSERT_NE(policy.by_certificate("gateway", none), nullptr);
  EXPECT_EQ(policy.by_certificate("gateway", none)->name, "gateway");
  ASSERT_NE(policy.by_certificate("some-host", san), nullptr);
  EXPECT_EQ(policy.by_certificate("some-host", san)->name, "trainer");
  EXPECT_EQ(policy.by_certificate("ops", none), nullptr);  // a token principal's name is no CN
}

TEST(AuthPolicy, AcceptsUppercaseHashesAsTheSameToken) {
  std::string upper = sha256_hex(kOpsToken);
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const auto policy = AuthPolicy::parse(R"({"principals": [{"name": "ops", "token_sha256": ")" +
                                            upper + R"(", "classes": ["reader"]}]})",
                                        "p.json");
  EXPECT_NE(policy.by_token(kOpsToken), nullptr);
}

TEST(AuthPolicy, RefusesWhatItDoesNotUnderstandNamingTheField) {
  const std::string hash = sha256_hex("t");
  auto parse = [](const std::string& text) {
    return [text] { AuthPolicy::parse(text, "p.json"); };
  };
  EXPECT_NE(refusal(parse("not json")).find("p.json"), std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principal": []})")).find("p.json: principals"), std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [], "extra": 1})")).find("p.json: extra"),
            std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [{"name": "a", "cert_cn": "a", "classes": ["reader"],
                                              "token": "plain"}]})"))
                .find("principals[0].token"),
            std::string::npos);
  EXPECT_NE(
      refusal(
          parse(R"({"principals": [{"name": "a", "token_sha256": "abc", "classes": ["reader"]}]})"))
          .find("principals[0].token_sha256"),
      std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [{"name": "a", "classes": ["reader"]}]})"))
                .find("at least one of token_sha256, cert_cn, cert_san"),
            std::string::npos);
  EXPECT_NE(
      refusal(parse(R"({"principals": [{"name": "a", "cert_cn": "a", "classes": ["admin"]}]})"))
          .find("principals[0].classes[0]"),
      std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [{"name": "a", "cert_cn": "a", "classes": []}]})"))
                .find("principals[0].classes"),
            std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [{"cert_cn": "a", "classes": ["reader"]}]})"))
                .find("principals[0].name"),
            std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [
                {"name": "a", "token_sha256": ")" +
                          hash + R"(", "classes": ["reader"]},
                {"name": "b", "token_sha256": ")" +
                          hash + R"(", "classes": ["operator"]}]})"))
                .find("principals[1].token_sha256"),
            std::string::npos);
  EXPECT_NE(refusal(parse(R"({"principals": [
                {"name": "a", "cert_cn": "x", "classes": ["reader"]},
                {"name": "a", "cert_cn": "y", "classes": ["reader"]}]})"))
                .find("principals[1].name"),
            std::string::npos);
}

TEST(AuthPolicy, RolesBindAPrincipalToKnownTrainingRolesOnly) {
  const auto policy = AuthPolicy::parse(
      R"({"principals": [{"name": "a", "cert_cn": "a", "classes": ["reader"],
                          "roles": ["approach", "hlc"]},
                         {"name": "b", "cert_cn": "b", "classes": ["reader"]}]})",
      "p.json");
  EXPECT_EQ(policy.principals()[0].roles, (std::set<std::string, std::less<>>{"approach", "hlc"}));
  EXPECT_TRUE(policy.principals()[1].roles.empty());  // every role
  auto parse = [](const std::string& roles) {
    return [roles] {
      AuthPolicy::parse(R"({"principals": [{"name": "a", "cert_cn": "a", "classes": ["reader"],
                                            "roles": )" +
                            roles + "}]}",
                        "p.json");
    };
  };
  EXPECT_NE(refusal(parse(R"(["aproach"])")).find("principals[0].roles[0]"), std::string::npos);
  // An empty list would read as "none" and mean "all": refused.
  EXPECT_NE(refusal(parse("[]")).find("principals[0].roles: expected a non-empty list"),
            std::string::npos);
  EXPECT_NE(refusal(parse(R"("approach")")).find("principals[0].roles"), std::string::npos);
}

TEST(AuthPolicy, AMissingPolicyFileIsNotFoundNamingTheFlag) {
  try {
    AuthPolicy::load("/nonexistent/policy.json");
    FAIL() << "loaded a file that does not exist";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(e.what()).find("--auth-policy"), std::string::npos);
  }
}

TEST(DecideAccess, NoCredentialsIsUnauthenticatedNamingTheRpc) {
  const auto d = decide(PresentedCredentials{}, kPromote);
  EXPECT_EQ(d.outcome, Outcome::kUnauthenticated);
  EXPECT_NE(d.message.find(kPromote), std::string::npos);
  EXPECT_NE(d.message.find("credentials required"), std::string::npos);
}

TEST(DecideAccess, AnUnknownOrMalformedTokenIsUnauthenticatedAndNeverEchoed) {
  const auto unknown = decide(token("guess-123"), kStatus);
  EXPECT_EQ(unknown.outcome, Outcome::kUnauthenticated);
  EXPECT_EQ(unknown.message.find("guess-123"), std::string::npos);
  PresentedCredentials malformed;
  malformed.malformed_authorization = true;
  EXPECT_EQ(decide(malformed, kStatus).outcome, Outcome::kUnauthenticated);
}

TEST(DecideAccess, AReaderMayReadButNotPromoteAndIsToldWhichClassItLacks) {
  EXPECT_EQ(decide(token(kReaderToken), kStatus).outcome, Outcome::kAllowed);
  const auto d = decide(token(kReaderToken), kPromote);
  EXPECT_EQ(d.outcome, Outcome::kPermissionDenied);
  EXPECT_EQ(d.principal, "dashboard");
  EXPECT_NE(d.message.find(kPromote), std::string::npos);
  EXPECT_NE(d.message.find("operator class"), std::string::npos);
  EXPECT_EQ(d.message.find(kReaderToken), std::string::npos);
}

TEST(DecideAccess, AnOperatorMayPromoteButNotMoveTheRobot) {
  const auto promote = decide(token(kOpsToken), kPromote);
  EXPECT_EQ(promote.outcome, Outcome::kAllowed);
  EXPECT_EQ(promote.principal, "ops");
  EXPECT_EQ(decide(token(kOpsToken), kStream).outcome, Outcome::kPermissionDenied);
}

TEST(DecideAccess, ACertificatePrincipalGetsItsClasses) {
  EXPECT_EQ(decide(certificate("gateway"), kStream).outcome, Outcome::kAllowed);
  EXPECT_EQ(decide(certificate("gateway"), kPromote).outcome, Outcome::kPermissionDenied);
  EXPECT_EQ(decide(certificate("stranger"), kStatus).outcome, Outcome::kUnauthenticated);
}

TEST(DecideAccess, AWrongTokenIsNotExcusedByAGoodCertificate) {
  PresentedCredentials both = certificate("gateway");
  both.bearer_token = "wrong";
  EXPECT_EQ(decide(both, kStream).outcome, Outcome::kUnauthenticated);
}

TEST(DecideAccess, EveryAuthenticatedPrincipalMayStopTheArm) {
  EXPECT_EQ(decide(token(kReaderToken), kStop).outcome, Outcome::kAllowed);
  EXPECT_EQ(decide(certificate("", {"trainer.pnp.internal"}), kStop).outcome, Outcome::kAllowed);
  EXPECT_EQ(decide(PresentedCredentials{}, kStop).outcome, Outcome::kUnauthenticated);
}

TEST(DecideAccess, AnRpcOutsideTheTableIsDeniedToEveryone) {
  const auto d = decide(token(kOpsToken), "/pnp.policy.v1.PolicyService/Unknown");
  EXPECT_EQ(d.outcome, Outcome::kPermissionDenied);
  EXPECT_NE(d.message.find("denied to everyone"), std::string::npos);
}

}  // namespace
}  // namespace pnp::security
