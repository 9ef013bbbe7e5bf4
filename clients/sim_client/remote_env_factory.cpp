#include "clients/sim_client/remote_env_factory.h"

#include <exception>

#include "clients/sim_client/remote_environment.h"
#include "common/error.h"

namespace pnp::sim_client {

RemoteEnvFactory::RemoteEnvFactory(const std::vector<std::string>& targets, sim::Robot robot,
                                   sim::ObjectShape object, sim::WorldProfile world,
                                   sim::Actuation actuation, const services::ClientTlsFiles& tls,
                                   std::chrono::milliseconds connect_timeout)
    : targets_(targets),
      robot_(robot),
      object_(object),
      world_(world),
      actuation_(actuation),
      tls_(tls),
      connect_timeout_(connect_timeout) {
  if (targets_.empty()) {
    throw Error(ErrorCode::kInvalidArgument,
                "sim_address: expected at least one simulation service address, got none");
  }
  // Malformed targets are refused now; whether a name resolves is asked at each make().
  for (const std::string& target : targets_) validate_sim_target(target);
  sim::require_supported(robot_, actuation_);
  services::validate(tls_);
}

std::vector<SimServerAddress> RemoteEnvFactory::servers_now() const {
  // A target that resolves to nothing now (a name with no ready Pod) leaves the others.
  std::vector<SimServerAddress> servers;
  std::string unresolved;
  for (const std::string& target : targets_) {
    try {
      for (SimServerAddress& server : resolve_sim_target(target)) {
        if (server.server_name.empty() || !tls_.server_name.empty())
          server.server_name = tls_.server_name;
        servers.push_back(std::move(server));
      }
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kUnavailable) throw;
      unresolved += (unresolved.empty() ? "" : "; ") + std::string(e.what());
    }
  }
  if (servers.empty()) throw Error(ErrorCode::kUnavailable, unresolved);
  return servers;
}

std::shared_ptr<grpc::Channel> RemoteEnvFactory::channel_to(const SimServerAddress& server) const {
  const std::lock_guard lock(channels_mutex_);
  auto& channel = channels_[server];
  if (!channel) {
    services::ClientTlsFiles tls = tls_;
    tls.server_name = server.server_name;
    channel = services::dial(server.address, tls);
  }
  return channel;
}

std::unique_ptr<sim::Environment> RemoteEnvFactory::make() const {
  const std::vector<SimServerAddress> servers = servers_now();
  const std::size_t first = next_.fetch_add(1);
  std::exception_ptr first_failure;
  for (std::size_t i = 0; i < servers.size(); ++i) {
    const SimServerAddress& server = servers[(first + i) % servers.size()];
    try {
      return std::make_unique<RemoteEnvironment>(channel_to(server), server.address, robot_,
                                                 object_, world_, actuation_, connect_timeout_);
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kUnavailable) throw;  // includes a deadline passed
      if (!first_failure) first_failure = std::current_exception();
    }
  }
  std::rethrow_exception(first_failure);
}

}  // namespace pnp::sim_client
