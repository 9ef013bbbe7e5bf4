#pragma once
// Who may look: with an authorization policy (--auth-policy, the platform's), every page
// and API call needs a principal of the reader class, recognised by a bearer token sent
// as `Authorization: Bearer ...` (scripts) or as the `pnp_token` cookie a browser gets
// from /login. Without a policy (loopback, or TLS for a trusted network) anyone who can
// reach the port may read.

#include <httplib.h>

#include <memory>
#include <string>

#include "security/auth_policy.h"

namespace pnp::dashboard {

inline constexpr const char* kTokenCookie = "pnp_token";

class DashboardAccess {
 public:
  explicit DashboardAccess(std::shared_ptr<const security::AuthPolicy> policy);

  bool enforced() const { return policy_ != nullptr; }

  // The decision for one request (allowed when no policy is configured). The message
  // names what is needed, never a token.
  security::AccessDecision decide(const httplib::Request& request) const;

  // Whether `token` is a reader's: what /login accepts before it sets the cookie.
  bool is_reader_token(const std::string& token) const;

 private:
  std::shared_ptr<const security::AuthPolicy> policy_;
};

// Whether a token can travel in a cookie as it is (the platform's tokens are hex).
bool is_cookie_safe(const std::string& token);

// The value of cookie `name` in a Cookie header ("a=1; pnp_token=x"); empty if absent.
std::string cookie_value(const std::string& header, const std::string& name);

}  // namespace pnp::dashboard
