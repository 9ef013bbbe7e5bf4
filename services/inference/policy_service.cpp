#include "services/inference/policy_service.h"

#include "services/common/convert.h"
#include "services/common/status.h"

namespace pnp::services {
namespace {

void fill(const serving::Decision& d, policy::v1::PredictResponse& out) {
  out.set_subtask(d.subtask ? to_proto(*d.subtask) : common::v1::SUBTASK_UNSPECIFIED);
  to_proto(d.action, *out.mutable_action());
  out.set_value(d.value);
  out.clear_subtask_probabilities();
  if (d.probabilities)
    for (double p : *d.probabilities) out.add_subtask_probabilities(p);
  out.set_choreographer_checkpoint_id(d.choreographer_checkpoint_id);
  out.set_expert_checkpoint_id(d.expert_checkpoint_id);
}

bool serves_role(serving::PolicyKind kind, const std::string& role) {
  for (const std::string& r : serving::served_roles(kind))
    if (r == role) return true;
  return false;
}

}  // namespace

PolicyServiceImpl::PolicyServiceImpl(const std::string& db_path, serving::PolicyKind kind)
    : kind_(kind), store_(db_path) {
  try {
    reload();
  } catch (const Error&) {  // nothing promoted yet: serve once something is
  }
}

bool PolicyServiceImpl::reload() {
  std::lock_guard lock(store_mutex_);
  const auto ids = serving::promoted_checkpoint_ids(store_, kind_);
  const auto current = served_.load();
  if (ids && current && current->checkpoint_ids() == *ids) return false;
  auto next = serving::load_promoted(store_, kind_);
  served_.store(std::move(next));
  return true;
}

std::vector<serving::BatchStats> PolicyServiceImpl::batch_stats() const {
  const auto served = served_.load();
  return served ? served->batch_stats()
                : std::vector<serving::BatchStats>(serving::batched_actors(kind_).size());
}

std::shared_ptr<const serving::ServedPolicy> PolicyServiceImpl::served_or_unavailable() const {
  auto served = served_.load();
  if (served) return served;
  if (kind_ == serving::PolicyKind::kEndToEnd) {
    throw Error(ErrorCode::kFailedPrecondition,
                "no end-to-end policy is served yet: promote an e2e checkpoint");
  }
  throw Error(ErrorCode::kFailedPrecondition,
              "no hierarchy is served yet: promote an approach, manipulate, retract and hlc "
              "checkpoint");
}

grpc::Status PolicyServiceImpl::Predict(grpc::ServerContext*,
                                        const policy::v1::PredictRequest* request,
                                        policy::v1::PredictResponse* response) {
  return guarded([&] {
    const sim::Observation observation = from_proto(request->observation(), "observation");
    const sim::Goal goal = from_proto(request->goal(), "goal");
    const auto served = served_or_unavailable();
    auto controller = served->acquire();
    fill(controller->act(observation, goal), *response);
    return grpc::Status::OK;
  });
}

grpc::Status PolicyServiceImpl::PredictSession(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<policy::v1::PredictSessionResponse, policy::v1::PredictSessionRequest>*
        stream) {
  return guarded([&] {
    // The whole episode runs on the policy served when it began.
    const auto served = served_or_unavailable();
    auto controller = served->acquire();
    policy::v1::PredictSessionRequest request;
    policy::v1::PredictSessionResponse response;
    while (!context->IsCancelled() && stream->Read(&request)) {
      const sim::Observation observation = from_proto(request.observation(), "observation");
      const sim::Goal goal = from_proto(request.goal(), "goal");
      const auto d = controller->act(observation, goal);
      fill(d, *response.mutable_prediction());
      response.set_decided(d.decided);
      response.set_placed(d.placed);
      response.set_step(controller->steps());
      if (!stream->Write(response)) break;
    }
    if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
    return grpc::Status::OK;
  });
}

grpc::Status PolicyServiceImpl::PromoteCheckpoint(
    grpc::ServerContext*, const policy::v1::PromoteCheckpointRequest* request,
    policy::v1::PromoteCheckpointResponse* response) {
  return guarded([&] {
    if (request->checkpoint_id() <= 0) {
      throw_invalid_argument("checkpoint_id", "a positive id",
                             std::to_string(request->checkpoint_id()));
    }
    store::Promotion promotion;
    store::CheckpointInfo info;
    std::optional<store::CheckpointInfo> latest;
    {
      std::lock_guard lock(store_mutex_);
      promotion = store_.promote(request->checkpoint_id());
      info = store_.checkpoint_info(promotion.checkpoint_id);
      latest = store_.latest_checkpoint(info.run_id);
    }
    response->set_role(role_from_name(promotion.role));
    response->set_checkpoint_id(promotion.checkpoint_id);
    response->set_run_id(info.run_id);
    response->set_env_steps(info.env_steps);
    response->set_latest_of_run(latest && latest->id == info.id);
    // Serve it now if it completes (or changes) the served kind's roles; a role the kind
    // does not use changes nothing, an incomplete hierarchy keeps the old one.
    try {
      reload();
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kFailedPrecondition) throw;
    }
    return grpc::Status::OK;
  });
}

grpc::Status PolicyServiceImpl::GetServingStatus(grpc::ServerContext*,
                                                 const policy::v1::GetServingStatusRequest*,
                                                 policy::v1::GetServingStatusResponse* response) {
  return guarded([&] {
    std::lock_guard lock(store_mutex_);
    // The roles of the served kind only: the others serve nothing here.
    for (const store::Promotion& p : store_.promotions()) {
      if (!serves_role(kind_, p.role)) continue;
      auto* role = response->add_roles();
      role->set_role(role_from_name(p.role));
      role->set_checkpoint_id(p.checkpoint_id);
      role->mutable_promote_time()->set_seconds(p.promoted_ms / 1000);
      role->mutable_promote_time()->set_nanos(static_cast<int>(p.promoted_ms % 1000) * 1'000'000);
    }
    const auto served = served_.load();
    response->set_ready(served != nullptr);
    if (served) {
      for (auto& role : *response->mutable_roles()) {
        role.set_robot(to_proto(served->robot()));
        role.set_object(to_proto(served->object()));
        role.set_world(to_proto(served->world()));
      }
    }
    return grpc::Status::OK;
  });
}

grpc::Status PolicyServiceImpl::Ping(grpc::ServerContext*, const policy::v1::PingRequest*,
                                     policy::v1::PingResponse*) {
  return grpc::Status::OK;
}

}  // namespace pnp::services
