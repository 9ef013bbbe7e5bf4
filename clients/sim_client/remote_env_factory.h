#pragma once
// Environments spread over simulation services: each make() opens a new environment on
// the next server in turn, so a trainer's parallel rollouts scale out across machines.
// Each target is one server or a pool resolved afresh at every make() (sim_target.h), so a
// pool that grows or shrinks is followed without a restart. Which server runs an episode
// does not change it: every episode is seeded by the trainer.

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "clients/sim_client/sim_target.h"
#include "services/common/transport_security.h"
#include "sim/env_factory.h"

namespace pnp::sim_client {

class RemoteEnvFactory final : public sim::EnvFactory {
 public:
  // targets: at least one (INVALID_ARGUMENT otherwise, and for a malformed one), all
  // dialled with `tls` (plaintext by default).
  RemoteEnvFactory(const std::vector<std::string>& targets, sim::Robot robot,
                   sim::ObjectShape object, sim::WorldProfile world = sim::WorldProfile::kPaper,
                   sim::Actuation actuation = sim::Actuation::kMocap,
                   const services::ClientTlsFiles& tls = {},
                   std::chrono::milliseconds connect_timeout = std::chrono::seconds(10));
  // On the next server in turn; a server that cannot open one (UNAVAILABLE, or no answer
  // within the connect timeout) passes the turn to the next, and the error is the first
  // server's when none can.
  std::unique_ptr<sim::Environment> make() const override;
  sim::Robot robot() const override { return robot_; }
  sim::ObjectShape object() const override { return object_; }
  sim::WorldProfile profile() const override { return world_; }
  sim::Actuation actuation() const override { return actuation_; }

 private:
  std::vector<SimServerAddress> servers_now() const;
  std::shared_ptr<grpc::Channel> channel_to(const SimServerAddress& server) const;

  std::vector<std::string> targets_;
  sim::Robot robot_;
  sim::ObjectShape object_;
  sim::WorldProfile world_;
  sim::Actuation actuation_;
  services::ClientTlsFiles tls_;
  std::chrono::milliseconds connect_timeout_;
  mutable std::atomic<std::size_t> next_{0};
  // One channel per server, shared by its environments (their streams multiplex over one
  // HTTP/2 connection), kept while the process lives: a server that left costs an idle
  // channel, one that returns at the same address reuses it.
  mutable std::mutex channels_mutex_;
  mutable std::map<SimServerAddress, std::shared_ptr<grpc::Channel>> channels_;
};

}  // namespace pnp::sim_client
