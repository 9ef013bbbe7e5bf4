#pragma once
// Who may call what: the authorization policy a server loads with --auth-policy FILE.
//
//   {"principals": [
//     {"name": "ops", "token_sha256": "<64 hex>", "classes": ["reader", "operator"]},
//     {"name": "gateway", "cert_cn": "gateway", "classes": ["agent", "robot"]},
//     {"name": "approach", "cert_cn": "approach", "classes": ["reader", "agent", "service"],
//      "roles": ["approach"]}]}
//
// A principal is recognised by a bearer token (stored as its SHA-256 only, compared in
// constant time) and/or by its mutual-TLS client certificate (subject CN, or a SAN).
// Parsing refuses anything it does not understand (an unknown key, class or a malformed
// hash), naming the field: a typo in a security policy must not silently grant or deny.

#include <functional>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "security/access_class.h"

namespace pnp::security {

struct PolicyPrincipal {
  std::string name;
  std::string token_sha256;  // lowercase hex; empty: no token
  std::string cert_cn;       // empty: not by certificate subject
  std::string cert_san;      // empty: not by certificate SAN
  std::set<AccessClass> classes;
  // The training roles whose runs it may create, claim and count (common/roles.h): a
  // trainer's identity bound to its own queue, so that breaking into the approach Pod does
  // not give the retract runs. Empty: every role.
  std::set<std::string, std::less<>> roles{};
};

class AuthPolicy {
 public:
  // `source` names the policy in errors (a file name).
  static AuthPolicy parse(std::string_view json_text, std::string_view source);
  static AuthPolicy load(const std::string& path);  // NOT_FOUND / INVALID_ARGUMENT

  // The principal whose token this is; nullptr if none (every entry is compared, so the
  // time does not say which entry came close).
  const PolicyPrincipal* by_token(std::string_view token) const;
  // The principal a verified client certificate names: its subject CN (`common_name`) or
  // one of its SANs; nullptr if none.
  const PolicyPrincipal* by_certificate(std::string_view common_name,
                                        std::span<const std::string> sans) const;
  const std::vector<PolicyPrincipal>& principals() const { return principals_; }

 private:
  std::vector<PolicyPrincipal> principals_;
};

// What a caller presented: a bearer token (from `authorization: Bearer ...`) and/or the
// identities of a verified client certificate.
struct PresentedCredentials {
  std::optional<std::string> bearer_token;  // set if an authorization header was sent
  bool malformed_authorization = false;     // a header that is not "Bearer <token>"
  std::string cert_common_name;             // empty: no client certificate
  std::vector<std::string> cert_sans;
};

struct AccessDecision {
  enum class Outcome { kAllowed, kUnauthenticated, kPermissionDenied };
  Outcome outcome = Outcome::kUnauthenticated;
  std::string principal;  // who, when recognised
  std::string message;    // for the caller: names the RPC and what it needs, never a token
  std::set<AccessClass> classes{};             // what the policy grants them, when allowed
  std::set<std::string, std::less<>> roles{};  // the roles they are bound to (empty: all)
};

// Decides one call of `rpc` (its method path) that requires `requirement`; `requirement`
// empty means the RPC is not in the table: denied. A bearer token, when sent, decides who
// the caller is (a wrong one is never excused by a certificate).
AccessDecision decide_access(const AuthPolicy& policy, const PresentedCredentials& presented,
                             std::string_view rpc,
                             const std::optional<RpcRequirement>& requirement);

}  // namespace pnp::security
