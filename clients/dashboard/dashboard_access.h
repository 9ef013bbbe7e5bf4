#pragma once
// Who may look: with an authorization policy (--auth-policy, the platform's), every page
// and API call needs a principal of the reader class, recognised by a bearer token sent
// as `Authorization: Bearer ...` (scripts) or, in a browser, by the session cookie
// /login sets once it has checked a reader's token (session_book.h: the token itself
// never goes into the browser's cookie). Without a policy (loopback, or TLS for a
// trusted network) anyone who can reach the port may read.

#include <httplib.h>

#include <memory>
#include <optional>
#include <string>

#include "clients/dashboard/session_book.h"
#include "security/auth_policy.h"

namespace pnp::dashboard {

inline constexpr const char* kSessionCookie = "pnp_session";
inline constexpr const char* kLoginCookie = "pnp_login";  // the login form's nonce

// A browser sign-in: the new session's id, or why the token was refused.
struct SignIn {
  std::optional<std::string> session_id;
  std::string refusal;  // for the login page; never the token
};

class DashboardAccess {
 public:
  explicit DashboardAccess(std::shared_ptr<const security::AuthPolicy> policy,
                           std::chrono::seconds session_lifetime = SessionBook::kDefaultLifetime);

  bool enforced() const { return policy_ != nullptr; }

  // The decision for one request (allowed when no policy is configured). The message
  // names what is needed, never a token.
  security::AccessDecision decide(const httplib::Request& request);

  // A session for `token` if it is a reader's that may go into a browser: a token whose
  // principal may operate the platform or move the arm (operator, robot, service,
  // delegate) is refused, since a browser keeps what it is given.
  SignIn sign_in(const std::string& token);

  SessionBook& sessions() { return sessions_; }

 private:
  std::shared_ptr<const security::AuthPolicy> policy_;
  SessionBook sessions_;
};

// The value of cookie `name` in a Cookie header ("a=1; pnp_token=x"); empty if absent.
std::string cookie_value(const std::string& header, const std::string& name);

}  // namespace pnp::dashboard
