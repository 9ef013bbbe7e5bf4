#pragma once
// Where a trainer's rollouts go: one `--sim-address` names one simulation server or a
// pool of them, resolved again each time an environment is opened, so that servers that
// joined since (a Deployment scaled up) take new environments and ones that left do not.
//
//   host:port            one server, dialled by its name
//   dns:///host:port     every address the name resolves to (a headless Service's Pods);
//                        their certificates are verified against `host`
//   ipv4:a:p,b:p         a fixed list, in gRPC's own syntax (also ipv6:[a]:p,[b]:p)
//
// Not gRPC's round_robin: an environment's CreateEnv and its rollout stream must reach the
// same server, and a balancer promises nothing across two calls. Each member gets its own
// channel instead, and an environment stays on the member that created it.

#include <string>
#include <string_view>
#include <vector>

namespace pnp::sim_client {

struct SimServerAddress {
  std::string address;      // what is dialled: host:port, ipv4:a:p or ipv6:[a]:p
  std::string server_name;  // the name its certificate must carry; empty: the host dialled
  auto operator<=>(const SimServerAddress&) const = default;
};

// INVALID_ARGUMENT naming `field` unless `target` has one of the forms above (nothing is
// resolved).
void validate_sim_target(const std::string& target, std::string_view field = "sim_address");

// The servers `target` names now, sorted (so turns over them are stable while the set is),
// without duplicates. INVALID_ARGUMENT naming sim_address for a malformed target;
// UNAVAILABLE when a dns:/// name resolves to nothing.
std::vector<SimServerAddress> resolve_sim_target(const std::string& target);

}  // namespace pnp::sim_client
