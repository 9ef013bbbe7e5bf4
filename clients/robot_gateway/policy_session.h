#pragma once
// One episode's PredictSession stream to the inference service: the choreographer's
// recurrent state lives on the server for as long as the stream is open. The gateway asks
// and then waits with a deadline (its dead-man timeout); a session that has missed one
// is not used again, since a late answer would pair with the wrong request.

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <memory>
#include <optional>

#include "clients/robot_gateway/stream_mailbox.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "sim/observation.h"

namespace pnp::gateway {

struct Prediction {
  sim::Action action = sim::Action::Zero();  // as received: not trusted, checked later
  bool placed = false;
  int subtask = 0;  // pnp.common.v1.Subtask value
};

class PolicySession {
 public:
  // episode_steps: how long the episode lasts, declared to the policy (its subtask caps
  // scale to it).
  PolicySession(policy::v1::PolicyService::Stub& stub, int episode_steps);
  ~PolicySession();  // cancels the stream if still open
  PolicySession(const PolicySession&) = delete;
  PolicySession& operator=(const PolicySession&) = delete;

  // false when the stream has broken (the server went away).
  bool ask(const sim::Observation& observation, const sim::Goal& goal);
  // nullopt when the deadline passes or `interrupted` is set first.
  std::optional<Prediction> answer(std::chrono::steady_clock::time_point deadline,
                                   const std::atomic<bool>& interrupted);
  // Why the stream ended, once it has (the server's status).
  grpc::Status finish();

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<policy::v1::PredictSessionRequest,
                                           policy::v1::PredictSessionResponse>>
      stream_;
  std::optional<StreamMailbox<policy::v1::PredictSessionResponse>> answers_;
  policy::v1::PredictSessionRequest request_;
  bool finished_ = false;
};

}  // namespace pnp::gateway
