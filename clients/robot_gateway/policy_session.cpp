#include "clients/robot_gateway/policy_session.h"

#include "services/common/convert.h"

namespace pnp::gateway {

PolicySession::PolicySession(policy::v1::PolicyService::Stub& stub, int episode_steps)
    : stream_(stub.PredictSession(&context_)) {
  request_.set_episode_steps(episode_steps);
  answers_.emplace([this](policy::v1::PredictSessionResponse& m) { return stream_->Read(&m); });
}

PolicySession::~PolicySession() {
  if (!finished_) {
    context_.TryCancel();
    answers_.reset();  // joins the reader, which the cancellation has released
    stream_->Finish().ok();
  }
}

bool PolicySession::ask(const sim::Observation& observation, const sim::Goal& goal) {
  services::to_proto(observation, *request_.mutable_observation());
  services::to_proto(Eigen::Vector3d(goal), *request_.mutable_goal());
  return stream_->Write(request_);
}

std::optional<Prediction> PolicySession::answer(std::chrono::steady_clock::time_point deadline,
                                                const std::atomic<bool>& interrupted) {
  const auto response = answers_->next(deadline, &interrupted);
  if (!response) return std::nullopt;
  const auto& a = response->prediction().action();
  Prediction p;
  p.action << a.dx(), a.dy(), a.dz(), a.gripper();
  p.placed = response->placed();
  p.subtask = response->prediction().subtask();
  return p;
}

grpc::Status PolicySession::finish() {
  stream_->WritesDone();
  answers_.reset();
  finished_ = true;
  return stream_->Finish();
}

}  // namespace pnp::gateway
