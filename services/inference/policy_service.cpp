#include "services/inference/policy_service.h"

#include <chrono>
#include <filesystem>
#include <optional>
#include <vector>

#include "rl/checkpoint_probe.h"
#include "services/common/access_control.h"
#include "services/common/convert.h"
#include "services/common/status.h"
#include "store/run_store.h"
#include "store/schema.h"

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

namespace {

// The serving connection is read-only: serving never writes, and a store on a read-only
// file (or a replica's copy) is served. A new file (--create-db) or an older schema is
// first set up read-write, once.
std::unique_ptr<store::Store> open_for_serving(const std::string& path) {
  if (path == ":memory:") return std::make_unique<store::RunStore>(path);
  const bool current = std::filesystem::exists(path) && [&] {
    store::Database probe(path, {.access = store::Access::kReadOnly});
    return probe.pragma_int("user_version") >= store::schema_version();
  }();
  if (!current) store::RunStore migrate_once(path);
  return std::make_unique<store::RunStore>(
      path, store::DatabaseOptions{.access = store::Access::kReadOnly});
}

// 50 us to 1 s, with 2 ms a bound: the alert on a 2 ms p99 reads an exact bucket.
const std::vector<double>& session_step_bounds() {
  static const std::vector<double> bounds = {50e-6,  100e-6, 250e-6, 500e-6, 1e-3, 2e-3,
                                             2.5e-3, 5e-3,   10e-3,  25e-3,  0.1,  1};
  return bounds;
}

}  // namespace

PolicyServiceImpl::PolicyServiceImpl(const std::string& db_path, serving::PolicyKind kind,
                                     StreamLimits* limits, MetricsRegistry* metrics)
    : PolicyServiceImpl([db_path] { return open_for_serving(db_path); },
                        [db_path]() -> std::unique_ptr<store::Store> {
                          return std::make_unique<store::RunStore>(db_path);
                        },
                        kind, limits, metrics) {}

PolicyServiceImpl::PolicyServiceImpl(store::StoreOpener open_store, serving::PolicyKind kind,
                                     StreamLimits* limits, MetricsRegistry* metrics)
    : PolicyServiceImpl(open_store, open_store, kind, limits, metrics) {}

PolicyServiceImpl::PolicyServiceImpl(store::StoreOpener open_reader, store::StoreOpener open_writer,
                                     serving::PolicyKind kind, StreamLimits* limits,
                                     MetricsRegistry* metrics)
    : kind_(kind),
      open_writer_(std::move(open_writer)),
      limits_(limits),
      session_step_seconds_(
          metrics ? &metrics->histogram("pnp_inference_session_step_seconds",
                                        "Time in the server of one PredictSession answer, from "
                                        "its request read to its answer written, in seconds.",
                                        session_step_bounds())
                  : nullptr),
      store_(open_reader()) {
  try {
    reload();
  } catch (const Error& e) {
    // Nothing promoted yet, or a promoted checkpoint that cannot be served (corrupted):
    // start serving nothing, and say why to every caller until a reload succeeds. Any
    // other error (the store cannot be read) stops the server at start.
    if (e.code() != ErrorCode::kFailedPrecondition && e.code() != ErrorCode::kDataLoss) throw;
    std::lock_guard lock(store_mutex_);
    load_error_ = e.what();
  }
}

bool PolicyServiceImpl::reload() {
  std::lock_guard lock(store_mutex_);
  // One consistent set of promotions (a promotion of several roles is seen whole or not
  // at all), then the checkpoints it names, which never change once written.
  const std::vector<store::Promotion> promotions = store_->promotions();
  const auto ids = serving::promoted_checkpoint_ids(promotions, kind_);
  const auto current = served_.load();
  if (ids && current && current->checkpoint_ids() == *ids) return false;
  try {
    auto next = serving::load_promoted(*store_, promotions, kind_);
    served_.store(std::move(next));
    load_error_.clear();
  } catch (const Error& e) {
    load_error_ = e.what();
    throw;
  }
  return true;
}

std::vector<serving::BatchStats> PolicyServiceImpl::batch_stats() const {
  const auto served = served_.load();
  return served ? served->batch_stats()
                : std::vector<serving::BatchStats>(serving::batched_actors(kind_).size());
}

std::shared_ptr<const serving::ServedPolicy> PolicyServiceImpl::served_or_unavailable() {
  auto served = served_.load();
  if (served) return served;
  std::string why;
  {
    std::lock_guard lock(store_mutex_);
    if (!load_error_.empty()) why = " (loading the promoted one failed: " + load_error_ + ")";
  }
  if (kind_ == serving::PolicyKind::kEndToEnd) {
    throw Error(ErrorCode::kFailedPrecondition,
                "no end-to-end policy is served yet" + why + ": promote an e2e checkpoint");
  }
  throw Error(ErrorCode::kFailedPrecondition,
              "no hierarchy is served yet" + why +
                  ": promote an approach, manipulate, retract and hlc checkpoint");
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
    auto slot = admit_stream(limits_, *context, "PredictSession");
    // The whole episode runs on the policy served when it began.
    const auto served = served_or_unavailable();
    policy::v1::PredictSessionRequest request;
    policy::v1::PredictSessionResponse response;
    std::optional<serving::ServedPolicy::Lease> controller;
    while (!context->IsCancelled() && stream->Read(&request)) {
      const auto arrived = std::chrono::steady_clock::now();
      slot.touch();
      // The first request declares the episode's length; the rest may only repeat it.
      if (!controller) {
        controller.emplace(served->acquire(request.episode_steps()));
      } else if (request.episode_steps() != 0 &&
                 request.episode_steps() != (*controller)->episode_steps()) {
        throw_invalid_argument("episode_steps",
                               "0 or the session's " +
                                   std::to_string((*controller)->episode_steps()) +
                                   " (declared by its first request)",
                               std::to_string(request.episode_steps()));
      }
      const sim::Observation observation = from_proto(request.observation(), "observation");
      const sim::Goal goal = from_proto(request.goal(), "goal");
      const auto d = (*controller)->act(observation, goal);
      fill(d, *response.mutable_prediction());
      response.set_decided(d.decided);
      response.set_placed(d.placed);
      response.set_step((*controller)->steps());
      if (!stream->Write(response)) break;
      if (session_step_seconds_)
        session_step_seconds_->Observe(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - arrived).count());
    }
    if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
    return grpc::Status::OK;
  });
}

grpc::Status PolicyServiceImpl::PromoteCheckpoint(
    grpc::ServerContext* context, const policy::v1::PromoteCheckpointRequest* request,
    policy::v1::PromoteCheckpointResponse* response) {
  return guarded([&] {
    std::vector<std::int64_t> ids;
    const bool single = request->checkpoint_id() != 0 || request->checkpoint_ids().empty();
    if (single) ids.push_back(request->checkpoint_id());
    ids.insert(ids.end(), request->checkpoint_ids().begin(), request->checkpoint_ids().end());
    // ids[i]'s field: checkpoint_id, when used, comes first.
    const auto field = [&](std::size_t i) {
      const std::size_t first_listed = single ? 1 : 0;
      return i < first_listed ? std::string("checkpoint_id")
                              : "checkpoint_ids[" + std::to_string(i - first_listed) + "]";
    };
    for (std::size_t i = 0; i < ids.size(); ++i)
      if (ids[i] <= 0) throw_invalid_argument(field(i), "a positive id", std::to_string(ids[i]));
    {
      std::lock_guard lock(store_mutex_);
      if (!writer_) writer_ = open_writer_();  // the one write this service makes
      // Every replica loads what is promoted: a checkpoint none could serve is refused
      // before the promotion commits.
      for (std::size_t i = 0; i < ids.size(); ++i) {
        const store::Checkpoint checkpoint = writer_->load_checkpoint(ids[i]);
        rl::probe_checkpoint(writer_->get_run(checkpoint.info.run_id).spec.role, checkpoint.blob,
                             field(i) + " " + std::to_string(ids[i]));
      }
      for (const store::Promotion& promotion : writer_->promote(ids, principal_of(*context))) {
        const store::CheckpointInfo info = writer_->checkpoint_info(promotion.checkpoint_id);
        const auto latest = writer_->latest_checkpoint(info.run_id);
        auto* out = response->add_promoted();
        out->set_role(role_from_name(promotion.role));
        out->set_checkpoint_id(promotion.checkpoint_id);
        out->set_run_id(info.run_id);
        out->set_env_steps(info.env_steps);
        out->set_latest_of_run(latest && latest->id == info.id);
      }
    }
    const auto& first = response->promoted(0);
    response->set_role(first.role());
    response->set_checkpoint_id(first.checkpoint_id());
    response->set_run_id(first.run_id());
    response->set_env_steps(first.env_steps());
    response->set_latest_of_run(first.latest_of_run());
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
    for (const store::Promotion& p : store_->promotions()) {
      if (!serves_role(kind_, p.role)) continue;
      auto* role = response->add_roles();
      role->set_role(role_from_name(p.role));
      role->set_checkpoint_id(p.checkpoint_id);
      role->mutable_promote_time()->set_seconds(p.promoted_ms / 1000);
      role->mutable_promote_time()->set_nanos(static_cast<int>(p.promoted_ms % 1000) * 1'000'000);
      role->set_promoted_by(p.promoted_by);
    }
    const auto served = served_.load();
    response->set_ready(served != nullptr);
    if (served) {
      for (auto& role : *response->mutable_roles()) {
        role.set_robot(to_proto(served->robot()));
        role.set_object(to_proto(served->object()));
        role.set_world(to_proto(served->world()));
        role.set_actuation(to_proto(served->actuation()));
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
