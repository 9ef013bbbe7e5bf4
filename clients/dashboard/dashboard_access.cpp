#include "clients/dashboard/dashboard_access.h"

#include "security/access_class.h"

namespace pnp::dashboard {

DashboardAccess::DashboardAccess(std::shared_ptr<const security::AuthPolicy> policy)
    : policy_(std::move(policy)) {}

security::AccessDecision DashboardAccess::decide(const httplib::Request& request) const {
  if (!policy_) return {security::AccessDecision::Outcome::kAllowed, "", ""};
  security::PresentedCredentials presented;
  if (request.has_header("Authorization")) {
    const std::string header = request.get_header_value("Authorization");
    constexpr std::string_view kBearer = "Bearer ";
    if (header.size() > kBearer.size() && header.starts_with(kBearer))
      presented.bearer_token = header.substr(kBearer.size());
    else
      presented.malformed_authorization = true;
  } else if (const std::string token =
                 cookie_value(request.get_header_value("Cookie"), kTokenCookie);
             !token.empty()) {
    presented.bearer_token = token;
  }
  return security::decide_access(*policy_, presented, "GET " + request.path,
                                 security::RpcRequirement{security::AccessClass::kReader});
}

bool DashboardAccess::is_reader_token(const std::string& token) const {
  if (!policy_) return true;
  const security::PolicyPrincipal* principal = policy_->by_token(token);
  return principal != nullptr && principal->classes.contains(security::AccessClass::kReader);
}

bool is_cookie_safe(const std::string& token) {
  if (token.empty() || token.size() > 4096) return false;
  for (const char c : token) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.' || c == '~' || c == '+' || c == '/';
    if (!ok) return false;
  }
  return true;
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
