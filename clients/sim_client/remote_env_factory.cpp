#include "clients/sim_client/remote_env_factory.h"

#include "clients/sim_client/remote_environment.h"
#include "common/error.h"

namespace pnp::sim_client {

RemoteEnvFactory::RemoteEnvFactory(const std::vector<std::string>& addresses, sim::Robot robot,
                                   sim::ObjectShape object, sim::WorldProfile world,
                                   const services::ClientTlsFiles& tls,
                                   std::chrono::milliseconds connect_timeout)
    : robot_(robot), object_(object), world_(world), connect_timeout_(connect_timeout) {
  if (addresses.empty()) {
    throw Error(ErrorCode::kInvalidArgument,
                "sim_address: expected at least one simulation service address, got none");
  }
  for (const std::string& address : addresses) {
    if (address.empty())
      throw Error(ErrorCode::kInvalidArgument, "sim_address: expected host:port, got \"\"");
    // One channel per service, shared by its environments: their streams multiplex over
    // one HTTP/2 connection.
    services_.push_back({address, services::dial(address, tls)});
  }
}

std::unique_ptr<sim::Environment> RemoteEnvFactory::make() const {
  const Service& service = services_[next_.fetch_add(1) % services_.size()];
  return std::make_unique<RemoteEnvironment>(service.channel, service.address, robot_, object_,
                                             world_, connect_timeout_);
}

}  // namespace pnp::sim_client
