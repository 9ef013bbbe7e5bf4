#include "clients/sim_client/sim_target.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <memory>

#include "common/error.h"
#include "services/common/address.h"

namespace pnp::sim_client {
namespace {

constexpr std::string_view kField = "sim_address";

[[noreturn]] void refuse(const std::string& target, std::string_view expected,
                         std::string_view field = kField) {
  throw_invalid_argument(field, expected, "\"" + target + "\"");
}

// "host:port" split at the last colon; host unbracketed.
std::pair<std::string, std::string> split_host_port(const std::string& address,
                                                    std::string_view field = kField) {
  services::validate_address(address, field);
  const auto colon = address.rfind(':');
  std::string host = address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return {host, address.substr(colon + 1)};
}

// "dns:///host:port" -> "host:port", validated.
std::string dns_name(const std::string& target, std::string_view field) {
  if (!target.starts_with("dns:///")) refuse(target, "dns:///host:port", field);
  const std::string name = target.substr(std::string_view("dns:///").size());
  if (name.empty() || name.find('/') != std::string::npos)
    refuse(target, "dns:///host:port (no authority)", field);
  split_host_port(name, field);
  return name;
}

std::vector<SimServerAddress> resolve_dns(const std::string& target) {
  const auto [host, port] = split_host_port(dns_name(target, kField));
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV | AI_ADDRCONFIG;  // no IPv6 answers on an IPv4-only host
  addrinfo* found = nullptr;
  const int failed = ::getaddrinfo(host.c_str(), port.c_str(), &hints, &found);
  const std::unique_ptr<addrinfo, decltype(&::freeaddrinfo)> owned(found, &::freeaddrinfo);
  if (failed != 0) {
    throw Error(ErrorCode::kUnavailable, std::string(kField) + ": " + target +
                                             " resolves to no address (" + ::gai_strerror(failed) +
                                             ")");
  }
  std::vector<SimServerAddress> servers;
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    std::array<char, INET6_ADDRSTRLEN> text{};
    if (a->ai_family == AF_INET) {
      ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(a->ai_addr)->sin_addr, text.data(),
                  text.size());
      servers.push_back({"ipv4:" + std::string(text.data()) + ":" + port, host});
    } else if (a->ai_family == AF_INET6) {
      ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(a->ai_addr)->sin6_addr,
                  text.data(), text.size());
      servers.push_back({"ipv6:[" + std::string(text.data()) + "]:" + port, host});
    }
  }
  return servers;
}

std::vector<SimServerAddress> split_list(const std::string& target, std::string_view field) {
  const std::string scheme = target.substr(0, 5);  // ipv4: or ipv6:
  std::vector<SimServerAddress> servers;
  std::string_view rest = std::string_view(target).substr(scheme.size());
  while (true) {
    const auto comma = rest.find(',');
    const std::string member(rest.substr(0, comma));
    if (member.empty()) refuse(target, scheme + "address:port[,address:port...]", field);
    const auto [host, port] = split_host_port(member, field);
    // gRPC takes literal addresses only here (and brackets around IPv6 ones).
    std::array<unsigned char, sizeof(in6_addr)> parsed{};
    const bool ipv6 = scheme == "ipv6:";
    const bool bracketed = member.starts_with('[');
    if (bracketed != ipv6 ||
        ::inet_pton(ipv6 ? AF_INET6 : AF_INET, host.c_str(), parsed.data()) != 1) {
      refuse(target,
             ipv6 ? "ipv6:[address]:port,... with literal IPv6 addresses"
                  : "ipv4:address:port,... with literal IPv4 addresses",
             field);
    }
    servers.push_back({scheme + member, ""});
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return servers;
}

bool is_list(const std::string& target) {
  return target.starts_with("ipv4:") || target.starts_with("ipv6:");
}

}  // namespace

void validate_sim_target(const std::string& target, std::string_view field) {
  if (target.starts_with("dns:")) {
    dns_name(target, field);
  } else if (is_list(target)) {
    split_list(target, field);
  } else {
    if (target.empty()) refuse(target, "host:port", field);
    services::validate_address(target, field);
  }
}

std::vector<SimServerAddress> resolve_sim_target(const std::string& target) {
  validate_sim_target(target);
  std::vector<SimServerAddress> servers;
  if (target.starts_with("dns:")) {
    servers = resolve_dns(target);
  } else if (is_list(target)) {
    servers = split_list(target, kField);
  } else {
    servers.push_back({target, ""});
  }
  std::sort(servers.begin(), servers.end());
  servers.erase(std::unique(servers.begin(), servers.end()), servers.end());
  return servers;
}

}  // namespace pnp::sim_client
