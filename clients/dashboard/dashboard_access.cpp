#include "clients/dashboard/dashboard_access.h"

#include "security/access_class.h"

namespace pnp::dashboard {

namespace {

const security::PolicyPrincipal* by_name(const security::AuthPolicy& policy,
                                         const std::string& name) {
  for (const auto& p : policy.principals())
    if (p.name == name) return &p;
  return nullptr;
}

}  // namespace

DashboardAccess::DashboardAccess(std::shared_ptr<const security::AuthPolicy> policy,
                                 std::chrono::seconds session_lifetime)
    : policy_(std::move(policy)), sessions_(session_lifetime) {}

security::AccessDecision DashboardAccess::decide(const httplib::Request& request) {
  using Outcome = security::AccessDecision::Outcome;
  if (!policy_) return {Outcome::kAllowed, "", ""};
  security::PresentedCredentials presented;
  if (request.has_header("Authorization")) {
    const std::string header = request.get_header_value("Authorization");
    constexpr std::string_view kBearer = "Bearer ";
    if (header.size() > kBearer.size() && header.starts_with(kBearer))
      presented.bearer_token = header.substr(kBearer.size());
    else
      presented.malformed_authorization = true;
  } else if (const std::string id =
                 cookie_value(request.get_header_value("Cookie"), kSessionCookie);
             !id.empty()) {
    const auto principal = sessions_.principal(id);
    const security::PolicyPrincipal* who = principal ? by_name(*policy_, *principal) : nullptr;
    if (who == nullptr || !who->classes.contains(security::AccessClass::kReader)) {
      return {Outcome::kUnauthenticated, "",
              "GET " + request.path + ": the session expired or was closed: sign in again"};
    }
    return {Outcome::kAllowed, who->name, ""};
  }
  return security::decide_access(*policy_, presented, "GET " + request.path,
                                 security::RpcRequirement{security::AccessClass::kReader});
}

SignIn DashboardAccess::sign_in(const std::string& token) {
  using security::AccessClass;
  const security::PolicyPrincipal* who = policy_ ? policy_->by_token(token) : nullptr;
  if (who == nullptr || !who->classes.contains(AccessClass::kReader))
    return {std::nullopt, "that token is not a reader's in this dashboard's policy"};
  for (const AccessClass strong : {AccessClass::kOperator, AccessClass::kRobot,
                                   AccessClass::kService, AccessClass::kDelegate}) {
    if (who->classes.contains(strong)) {
      return {std::nullopt, "\"" + who->name + "\" may also act as " +
                                std::string(security::access_class_name(strong)) +
                                ": such a token never goes into a browser; sign in with a token "
                                "of the reader class only"};
    }
  }
  return {sessions_.open(who->name), ""};
}

std::string cookie_value(const std::string& header, const std::string& name) {
  std::string_view rest(header);
  while (!rest.empty()) {
    const auto end = rest.find(';');
    std::string_view pair = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
    while (!pair.empty() && pair.front() == ' ') pair.remove_prefix(1);
    if (pair.size() > name.size() && pair.starts_with(name) && pair[name.size()] == '=')
      return std::string(pair.substr(name.size() + 1));
  }
  return {};
}

}  // namespace pnp::dashboard
