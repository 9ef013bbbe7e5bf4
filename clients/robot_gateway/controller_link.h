#pragma once
// The gateway's side of pnp.robot.v1: the lease, the scene (simulated stand-in only), the
// controller's state and the drive stream. Each call has a deadline; a failed call is a
// pnp::Error naming the call and the address (services::throw_if_error).

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "clients/robot_gateway/stream_mailbox.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"

namespace pnp::gateway {

class ControllerLink {
 public:
  using Clock = std::chrono::steady_clock;

  ControllerLink(std::shared_ptr<grpc::Channel> channel, std::string address,
                 std::chrono::milliseconds rpc_timeout);
  ~ControllerLink();  // closes the stream and gives the lease back
  ControllerLink(const ControllerLink&) = delete;
  ControllerLink& operator=(const ControllerLink&) = delete;

  void acquire_lease(const std::string& client_name, std::chrono::milliseconds timeout);
  void release_lease();
  bool has_lease() const { return !lease_id_.empty(); }

  robot::v1::GetStateResponse state();
  robot::v1::ResetSceneResponse reset_scene(std::uint64_t seed);  // needs the lease
  robot::v1::StopResponse stop(const std::string& reason);
  void resume();

  // The drive stream: opened with the lease, then one feedback per target.
  void open_stream();
  bool send(const robot::v1::PoseTarget& target);  // false: the stream broke
  // nullopt when the deadline passes; an Error with the controller's status when it has
  // ended the stream.
  std::optional<robot::v1::ControllerFeedback> feedback(Clock::time_point deadline);
  void close_stream();

  const std::string& address() const { return address_; }

 private:
  std::unique_ptr<grpc::ClientContext> context(std::chrono::milliseconds timeout) const;

  std::string address_;
  std::chrono::milliseconds rpc_timeout_;
  std::unique_ptr<robot::v1::RobotControllerService::Stub> controller_;
  std::unique_ptr<robot::v1::SimulatedSceneService::Stub> scene_;
  std::string lease_id_;

  struct Stream;
  std::unique_ptr<Stream> stream_;
};

}  // namespace pnp::gateway
