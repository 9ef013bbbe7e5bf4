#include "security/auth_policy.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/error.h"
#include "common/roles.h"
#include "security/sha256.h"

namespace pnp::security {
namespace {

bool is_lower_hex_sha256(const std::string& s) {
  if (s.size() != 64) return false;
  for (const char c : s)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

std::string text_field(const nlohmann::json& entry, const char* key, const std::string& where) {
  if (!entry.contains(key)) return {};
  const auto& value = entry.at(key);
  if (!value.is_string() || value.get<std::string>().empty())
    throw_invalid_argument(where + "." + key, "a non-empty string", value.dump());
  return value.get<std::string>();
}

// "roles": optional, but when given a non-empty list of known roles: an empty list would
// read as "none" and mean "all".
std::set<std::string, std::less<>> parse_roles(const nlohmann::json& entry,
                                               const std::string& where) {
  std::set<std::string, std::less<>> roles;
  if (!entry.contains("roles")) return roles;
  const auto& list = entry.at("roles");
  const std::string expected = "a non-empty list of approach, manipulate, retract, hlc, e2e";
  if (!list.is_array() || list.empty())
    throw_invalid_argument(where + ".roles", expected, list.dump());
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_string() || !is_known_role(list[i].get<std::string>())) {
      throw_invalid_argument(where + ".roles[" + std::to_string(i) + "]",
                             "approach, manipulate, retract, hlc or e2e", list[i].dump());
    }
    roles.insert(list[i].get<std::string>());
  }
  return roles;
}

PolicyPrincipal parse_principal(const nlohmann::json& entry, const std::string& where) {
  if (!entry.is_object()) throw_invalid_argument(where, "an object", entry.dump());
  for (const auto& [key, value] : entry.items()) {
    if (key != "name" && key != "token_sha256" && key != "cert_cn" && key != "cert_san" &&
        key != "classes" && key != "roles") {
      throw_invalid_argument(where + "." + key,
                             "one of name, token_sha256, cert_cn, cert_san, classes, roles",
                             "an unknown key");
    }
  }
  PolicyPrincipal p;
  p.name = text_field(entry, "name", where);
  if (p.name.empty()) throw_invalid_argument(where + ".name", "a non-empty string", "none");
  // A run's owner is "<principal>/<instance>" (pnp-store-server): a '/' in a name would let
  // one principal spell another's runs.
  if (p.name.find('/') != std::string::npos)
    throw_invalid_argument(where + ".name", "a name without '/'", "\"" + p.name + "\"");
  p.token_sha256 = text_field(entry, "token_sha256", where);
  for (char& c : p.token_sha256)
    if (c >= 'A' && c <= 'F') c = static_cast<char>(c - 'A' + 'a');
  if (!p.token_sha256.empty() && !is_lower_hex_sha256(p.token_sha256)) {
    throw_invalid_argument(where + ".token_sha256",
                           "the token's SHA-256 as 64 hex digits (sha256sum of the token file)",
                           std::to_string(p.token_sha256.size()) + " characters");
  }
  p.cert_cn = text_field(entry, "cert_cn", where);
  p.cert_san = text_field(entry, "cert_san", where);
  if (p.token_sha256.empty() && p.cert_cn.empty() && p.cert_san.empty()) {
    throw_invalid_argument(where, "at least one of token_sha256, cert_cn, cert_san",
                           "none: no one could be this principal");
  }
  if (!entry.contains("classes") || !entry.at("classes").is_array() ||
      entry.at("classes").empty()) {
    throw_invalid_argument(where + ".classes", "a non-empty list of reader, agent, operator, robot",
                           entry.contains("classes") ? entry.at("classes").dump() : "none");
  }
  const auto& classes = entry.at("classes");
  for (std::size_t i = 0; i < classes.size(); ++i) {
    const std::string field = where + ".classes[" + std::to_string(i) + "]";
    const auto parsed =
        classes[i].is_string() ? parse_access_class(classes[i].get<std::string>()) : std::nullopt;
    if (!parsed)
      throw_invalid_argument(field, "reader, agent, operator or robot", classes[i].dump());
    p.classes.insert(*parsed);
  }
  p.roles = parse_roles(entry, where);
  return p;
}

}  // namespace

AuthPolicy AuthPolicy::parse(std::string_view json_text, std::string_view source) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw_invalid_argument(std::string(source), "an authorization policy in JSON", e.what());
  }
  if (!doc.is_object() || !doc.contains("principals") || !doc.at("principals").is_array())
    throw_invalid_argument(std::string(source) + ": principals", "a list of principals", "none");
  for (const auto& [key, value] : doc.items()) {
    if (key != "principals")
      throw_invalid_argument(std::string(source) + ": " + key, "only principals", "an unknown key");
  }
  AuthPolicy policy;
  const auto& list = doc.at("principals");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = std::string(source) + ": principals[" + std::to_string(i) + "]";
    PolicyPrincipal p = parse_principal(list[i], where);
    for (const PolicyPrincipal& other : policy.principals_) {
      if (other.name == p.name)
        throw_invalid_argument(where + ".name", "a name no other principal has", p.name);
      if (!p.token_sha256.empty() && other.token_sha256 == p.token_sha256) {
        throw_invalid_argument(where + ".token_sha256", "a token no other principal has",
                               "the token of " + other.name);
      }
    }
    policy.principals_.push_back(std::move(p));
  }
  return policy;
}

AuthPolicy AuthPolicy::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(ErrorCode::kNotFound, "--auth-policy: cannot read " + path);
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

const PolicyPrincipal* AuthPolicy::by_token(std::string_view token) const {
  const std::string hash = sha256_hex(token);
  const PolicyPrincipal* found = nullptr;
  for (const PolicyPrincipal& p : principals_) {
    if (p.token_sha256.empty()) continue;
    if (constant_time_equal(p.token_sha256, hash)) found = &p;
  }
  return found;
}

const PolicyPrincipal* AuthPolicy::by_certificate(std::string_view common_name,
                                                  std::span<const std::string> sans) const {
  for (const PolicyPrincipal& p : principals_) {
    if (!p.cert_cn.empty() && p.cert_cn == common_name) return &p;
    if (p.cert_san.empty()) continue;
    for (const std::string& san : sans)
      if (san == p.cert_san) return &p;
  }
  return nullptr;
}

AccessDecision decide_access(const AuthPolicy& policy, const PresentedCredentials& presented,
                             std::string_view rpc,
                             const std::optional<RpcRequirement>& requirement) {
  using Outcome = AccessDecision::Outcome;
  AccessDecision d;
  const PolicyPrincipal* who = nullptr;
  if (presented.malformed_authorization) {
    d.message = std::string(rpc) + ": the authorization header is not \"Bearer <token>\"";
    return d;
  }
  if (presented.bearer_token) {
    who = policy.by_token(*presented.bearer_token);
    if (!who) {
      d.message = std::string(rpc) + ": the bearer token is not known to this server's policy";
      return d;
    }
  } else if (!presented.cert_common_name.empty() || !presented.cert_sans.empty()) {
    who = policy.by_certificate(presented.cert_common_name, presented.cert_sans);
    if (!who) {
      d.message = std::string(rpc) + ": the client certificate (CN \"" +
                  presented.cert_common_name + "\") names no principal of this server's policy";
      return d;
    }
  } else {
    d.message = std::string(rpc) +
                ": credentials required (a bearer token, e.g. pnpctl --token-file, or a client "
                "certificate)";
    return d;
  }
  d.principal = who->name;
  if (!requirement) {
    d.outcome = Outcome::kPermissionDenied;
    d.message = std::string(rpc) + ": not an RPC this server's policy knows; denied to everyone";
    return d;
  }
  const auto granted = [&](const std::optional<AccessClass>& c) {
    return c && who->classes.contains(*c);
  };
  if (requirement->access_class && !granted(requirement->access_class) &&
      !granted(requirement->or_class)) {
    std::string needed = std::string(access_class_name(*requirement->access_class));
    if (requirement->or_class)
      needed += " or " + std::string(access_class_name(*requirement->or_class));
    d.outcome = Outcome::kPermissionDenied;
    d.message = std::string(rpc) + " needs the " + needed + " class, which principal \"" +
                who->name + "\" is not granted";
    return d;
  }
  d.outcome = Outcome::kAllowed;
  d.classes = who->classes;
  d.roles = who->roles;
  return d;
}

}  // namespace pnp::security
