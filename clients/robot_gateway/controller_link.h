#pragma once
// The gateway's side of pnp.robot.v1: the lease, the scene (simulated stand-in only), the
// controller's state and the drive stream. Every wait is bounded (a deadline per call)
// and, except Stop, gives way to the operator's interrupt within kInterruptPoll: an
// interrupted call throws Error(kCancelled). A failed call is a pnp::Error naming the
// call and the address (services::throw_if_error).

#include <grpcpp/grpcpp.h>

#include <atomic>
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
  // How often a waiting call looks at the interrupt flag: well inside one policy period.
  static constexpr std::chrono::milliseconds kInterruptPoll{5};
  // How long giving the lease back may take once the operator has interrupted.
  static constexpr std::chrono::milliseconds kReleaseAfterInterrupt{100};

  // `interrupted` (the operator's Ctrl-C) must outlive the link.
  ControllerLink(std::shared_ptr<grpc::Channel> channel, std::string address,
                 std::chrono::milliseconds rpc_timeout, const std::atomic<bool>& interrupted);
  ~ControllerLink();  // closes the stream and gives the lease back
  ControllerLink(const ControllerLink&) = delete;
  ControllerLink& operator=(const ControllerLink&) = delete;

  void acquire_lease(const std::string& client_name, std::chrono::milliseconds timeout);
  // Takes the lease again with the same name and timeout after it lapsed while nothing
  // moved (FAILED_PRECONDITION if another client holds it meanwhile).
  void reacquire_lease();
  void release_lease();
  bool has_lease() const { return !lease_id_.empty(); }
  const std::string& client_name() const { return client_name_; }
  const std::string& lease_id() const { return lease_id_; }

  // nullopt when the controller does not answer within `timeout` (a stall).
  std::optional<robot::v1::GetStateResponse> state(std::chrono::milliseconds timeout);
  robot::v1::GetStateResponse state();  // the call timeout: UNAVAILABLE when it passes
  robot::v1::ResetSceneResponse reset_scene(std::uint64_t seed);  // needs the lease
  // Not interruptible: it is what an interrupt does.
  robot::v1::StopResponse stop(const std::string& reason, robot::v1::StopKind kind,
                               std::chrono::milliseconds timeout);
  // Clears a protective stop with the lease.
  robot::v1::ResumeResponse clear_protective_stop();

  // The drive stream: opened with the lease, then one feedback per target.
  void open_stream();
  bool send(const robot::v1::PoseTarget& target);  // false: the stream broke
  // nullopt when the deadline passes; an Error with the controller's status when it has
  // ended the stream.
  std::optional<robot::v1::ControllerFeedback> feedback(Clock::time_point deadline);
  void close_stream();
  bool stream_open() const { return stream_ != nullptr; }

  const std::string& address() const { return address_; }

 private:
  // One unary call, waited for with `timeout` and the interrupt: nullopt on a deadline.
  template <typename Response, typename Start>
  std::optional<Response> call(const char* what, std::chrono::milliseconds timeout,
                               bool interruptible, Start start);

  std::string address_;
  std::chrono::milliseconds rpc_timeout_;
  const std::atomic<bool>& interrupted_;
  std::unique_ptr<robot::v1::RobotControllerService::Stub> controller_;
  std::unique_ptr<robot::v1::SimulatedSceneService::Stub> scene_;
  std::string lease_id_, client_name_;
  std::chrono::milliseconds lease_timeout_{0};

  struct Stream;
  std::unique_ptr<Stream> stream_;
};

}  // namespace pnp::gateway
