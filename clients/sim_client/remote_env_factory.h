#pragma once
// Environments spread over one or more simulation services: each make() opens a new
// environment on the next service in turn, so a trainer's parallel rollouts scale out
// across machines. Which service runs an episode does not change it: every episode is
// seeded by the trainer.

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "services/common/transport_security.h"
#include "sim/env_factory.h"

namespace pnp::sim_client {

class RemoteEnvFactory final : public sim::EnvFactory {
 public:
  // addresses: host:port of each service (at least one; INVALID_ARGUMENT otherwise), all
  // dialled with `tls` (plaintext by default).
  RemoteEnvFactory(const std::vector<std::string>& addresses, sim::Robot robot,
                   sim::ObjectShape object, sim::WorldProfile world = sim::WorldProfile::kPaper,
                   const services::ClientTlsFiles& tls = {},
                   std::chrono::milliseconds connect_timeout = std::chrono::seconds(10));
  std::unique_ptr<sim::Environment> make() const override;
  sim::Robot robot() const override { return robot_; }
  sim::ObjectShape object() const override { return object_; }
  sim::WorldProfile profile() const override { return world_; }

 private:
  struct Service {
    std::string address;
    std::shared_ptr<grpc::Channel> channel;
  };
  std::vector<Service> services_;
  sim::Robot robot_;
  sim::ObjectShape object_;
  sim::WorldProfile world_;
  std::chrono::milliseconds connect_timeout_;
  mutable std::atomic<std::size_t> next_{0};
};

}  // namespace pnp::sim_client
