#include "services/common/replica_channel.h"

#include <string>

#include "replica_service_config.h"

namespace pnp::services {

std::string_view replica_service_config() {
  return generated::kReplicaServiceConfig;
}

void balance_over_replicas(grpc::ChannelArguments& args) {
  args.SetServiceConfigJSON(std::string(replica_service_config()));
}

}  // namespace pnp::services
