#pragma once
// A pick-and-place environment whose physics runs in a simulation service
// (pnp.sim.v1.SimulationService), possibly on another machine: one environment of its
// own, driven over one rollout stream (a round trip per step, no per-call setup).
//
// It behaves as PickPlaceEnv does: the same episode for the same seed (the service
// resets from the seed sent), the same validation before anything is sent (so a refused
// call changes nothing), the same results bit for bit (doubles cross the wire
// unchanged). A failure of the service or the connection is UNAVAILABLE naming the
// address, and leaves the environment unusable.

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "sim/actuation.h"
#include "sim/environment.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_profile.h"

namespace pnp::sim_client {

class RemoteEnvironment final : public sim::Environment {
 public:
  // Creates the environment on the service; `connect_timeout` bounds that call.
  RemoteEnvironment(std::shared_ptr<grpc::Channel> channel, std::string address, sim::Robot robot,
                    sim::ObjectShape object, sim::WorldProfile world, sim::Actuation actuation,
                    std::chrono::milliseconds connect_timeout);
  ~RemoteEnvironment() override;  // ends the stream and closes the environment
  RemoteEnvironment(const RemoteEnvironment&) = delete;
  RemoteEnvironment& operator=(const RemoteEnvironment&) = delete;

  const sim::Observation& reset(std::uint64_t seed) override;
  sim::StepResult step(std::span<const double> action, std::span<const double> goal,
                       sim::Objective objective) override;
  using Environment::step;

  const sim::Observation& observation() const override { return observation_; }
  const sim::Goal& episode_goal() const override { return episode_goal_; }
  sim::TaskState task_state() const override;
  int elapsed_steps() const override { return elapsed_steps_; }
  bool needs_reset() const override { return needs_reset_; }
  int episode_steps() const override { return episode_steps_; }
  const std::string& env_id() const { return env_id_; }

 private:
  void exchange();  // request_ -> response_ over the stream
  [[noreturn]] void fail(const std::string& what, const grpc::Status& status);
  void take(const pnp::sim::v1::EnvState& state);

  std::unique_ptr<pnp::sim::v1::SimulationService::Stub> stub_;
  std::string address_;
  double object_width_m_;
  int episode_steps_;  // the actuation's (sim::episode_steps), as the service counts them
  std::string env_id_;
  grpc::ClientContext stream_context_;
  std::unique_ptr<grpc::ClientReaderWriter<pnp::sim::v1::StreamRolloutRequest,
                                           pnp::sim::v1::StreamRolloutResponse>>
      stream_;
  // Reused every step: protobuf keeps their storage, so a step allocates nothing new.
  pnp::sim::v1::StreamRolloutRequest request_;
  pnp::sim::v1::StreamRolloutResponse response_;
  sim::Observation observation_ = sim::Observation::Zero();
  sim::Goal episode_goal_ = sim::Goal::Zero();
  int elapsed_steps_ = 0;
  bool needs_reset_ = true;
  bool broken_ = false;
};

}  // namespace pnp::sim_client
