#include "services/common/replica_channel.h"

#include <string>

namespace pnp::services {

std::string_view replica_service_config() {
  return R"({
  "loadBalancingConfig": [{"round_robin": {}}],
  "methodConfig": [{
    "name": [
      {"service": "pnp.policy.v1.PolicyService", "method": "Predict"},
      {"service": "pnp.policy.v1.PolicyService", "method": "GetServingStatus"},
      {"service": "pnp.policy.v1.PolicyService", "method": "Ping"},
      {"service": "grpc.health.v1.Health", "method": "Check"}
    ],
    "retryPolicy": {
      "maxAttempts": 4,
      "initialBackoff": "0.01s",
      "maxBackoff": "0.2s",
      "backoffMultiplier": 2,
      "retryableStatusCodes": ["UNAVAILABLE"]
    }
  }]
})";
}

void balance_over_replicas(grpc::ChannelArguments& args) {
  args.SetServiceConfigJSON(std::string(replica_service_config()));
}

}  // namespace pnp::services
