#include "services/train/training_service.h"

#include <chrono>
#include <cmath>

#include "common/error.h"
#include "services/common/access_control.h"
#include "services/common/convert.h"
#include "services/common/status.h"
#include "services/train/train_convert.h"
#include "sim/object_shape.h"
#include "sim/robot.h"

namespace pnp::services {
namespace {

using namespace train::v1;

std::int64_t require_run_id(std::int64_t id) {
  if (id <= 0) throw_invalid_argument("run_id", "a positive run id", std::to_string(id));
  return id;
}

// How often a watch checks for a cancelled client while its run is quiet.
constexpr auto kWatchPoll = std::chrono::milliseconds(200);

}  // namespace

void TrainingServiceImpl::fill(const store::RunRecord& run, TrainingRun& out) {
  out.set_run_id(run.id);
  out.set_role(role_from_name(run.spec.role));
  out.set_algorithm(algorithm_from_name(run.spec.algorithm));
  out.set_robot(to_proto(sim::parse_robot(run.spec.robot)));
  out.set_object(to_proto(sim::parse_object(run.spec.object)));
  out.set_seed(run.spec.seed);
  out.set_state(to_proto(run.state));
  out.set_config_json(run.spec.config_json);
  out.set_code_commit(run.spec.code_commit);
  out.set_gemm_path(run.spec.gemm_path);
  out.set_parent_checkpoint_id(run.spec.parent_checkpoint_id.value_or(0));
  out.set_env_steps(run.env_steps);
  // A run created by a training service stores its spec; an imported one (a checkpoint
  // file brought into the store) has none, and shows no cap, target, world or actuation.
  const auto config = nlohmann::json::parse(run.spec.config_json, nullptr, false);
  if (config.is_object() && config.contains("spec")) {
    const training::TrainingSpec spec = training::spec_from_json(config["spec"]);
    out.set_max_steps(spec.stop.max_steps);
    out.set_target_success(spec.stop.target_success);
    out.set_world(to_proto(spec.world));
    out.set_actuation(to_proto(spec.actuation));
  }
  out.set_last_success(run.last_success);
  if (run.last_score) out.set_last_score(*run.last_score);
  out.set_reached(run.reached);
  out.set_steps_to_target(run.steps_to_target.value_or(0));
  const auto checkpoints = manager_.checkpoints(run.id);
  out.set_latest_checkpoint_id(checkpoints.empty() ? 0 : checkpoints.back().id);
  out.set_error(run.error);
  to_proto(run.wall, *out.mutable_wall_breakdown());
  set_millis(run.created_ms, *out.mutable_create_time());
  set_millis(run.updated_ms, *out.mutable_update_time());
  if (run.finished_ms) set_millis(*run.finished_ms, *out.mutable_finish_time());
  if (const auto eta = manager_.eta_s(run.id)) {
    const double seconds = std::floor(*eta);
    out.mutable_eta()->set_seconds(static_cast<std::int64_t>(seconds));
    out.mutable_eta()->set_nanos(static_cast<int>((*eta - seconds) * 1e9));
  }
}

grpc::Status TrainingServiceImpl::CreateTrainingRun(grpc::ServerContext* context,
                                                    const CreateTrainingRunRequest* request,
                                                    CreateTrainingRunResponse* response) {
  return guarded([&] {
    constexpr std::size_t kMaxRequestId = 128;
    if (request->request_id().size() > kMaxRequestId) {
      throw_invalid_argument("request_id", "at most 128 bytes",
                             std::to_string(request->request_id().size()) + " bytes");
    }
    // Scoped by the caller: one operator's key never returns another's run.
    const std::string principal = principal_of(*context);
    const std::string key = principal.empty() || request->request_id().empty()
                                ? request->request_id()
                                : principal + "/" + request->request_id();
    const auto [spec, refs] = from_proto(*request);
    fill(manager_.create(spec, refs, key), *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status TrainingServiceImpl::GetTrainingRun(grpc::ServerContext*,
                                                 const GetTrainingRunRequest* request,
                                                 GetTrainingRunResponse* response) {
  return guarded([&] {
    fill(manager_.get(require_run_id(request->run_id())), *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status TrainingServiceImpl::ListTrainingRuns(grpc::ServerContext*,
                                                   const ListTrainingRunsRequest* request,
                                                   ListTrainingRunsResponse* response) {
  return guarded([&] {
    store::RunFilter filter;
    filter.limit = request->page_size() == 0 ? 100 : request->page_size();
    if (filter.limit < 1 || filter.limit > 1000)
      throw_invalid_argument("page_size", "1 to 1000 (0: 100)",
                             std::to_string(request->page_size()));
    filter.before_id = run_id_from_page_token(request->page_token());
    if (request->state() != RUN_STATE_UNSPECIFIED)
      filter.state = from_proto(request->state(), "state");
    const auto runs = manager_.list(filter);
    for (const auto& run : runs) fill(run, *response->add_runs());
    if (static_cast<int>(runs.size()) == filter.limit)
      response->set_next_page_token(page_token_after(runs.back().id));
    return grpc::Status::OK;
  });
}

grpc::Status TrainingServiceImpl::CancelTrainingRun(grpc::ServerContext*,
                                                    const CancelTrainingRunRequest* request,
                                                    CancelTrainingRunResponse* response) {
  return guarded([&] {
    fill(manager_.cancel(require_run_id(request->run_id())), *response->mutable_run());
    return grpc::Status::OK;
  });
}

grpc::Status TrainingServiceImpl::WatchTrainingRun(
    grpc::ServerContext* context, const WatchTrainingRunRequest* request,
    grpc::ServerWriter<WatchTrainingRunResponse>* writer) {
  return guarded([&] {
    // A queued run's watch is quiet until the run starts: heartbeats keep it open.
    auto slot = admit_stream(limits_, *context, "WatchTrainingRun");
    const std::int64_t id = require_run_id(request->run_id());
    std::uint64_t seen = manager_.generation();
    store::RunRecord run = manager_.get(id);
    const auto so_far = manager_.metrics(id);  // the watch starts from now
    long long sent_steps = so_far.empty() ? -1 : so_far.back().env_steps;
    auto last_write = std::chrono::steady_clock::now();
    const auto send = [&](const store::MetricPoint* point, bool heartbeat) {
      WatchTrainingRunResponse message;
      fill(run, *message.mutable_run());
      if (point != nullptr) to_proto(*point, *message.mutable_metric());
      message.set_heartbeat(heartbeat);
      if (!writer->Write(message)) return false;
      last_write = std::chrono::steady_clock::now();
      slot.touch();
      return true;
    };
    if (!send(nullptr, false)) return grpc::Status(grpc::StatusCode::CANCELLED, "client gone");
    while (!store::is_terminal(run.state)) {
      if (context->IsCancelled())
        return grpc::Status(grpc::StatusCode::CANCELLED, "watch cancelled by the client");
      seen = manager_.wait_for_change(seen, kWatchPoll);
      run = manager_.get(id);
      const auto metrics = manager_.metrics_after(id, sent_steps);  // the new points only
      for (const auto& point : metrics) {
        sent_steps = point.env_steps;
        if (!send(&point, false)) return grpc::Status(grpc::StatusCode::CANCELLED, "client gone");
      }
      const bool finished = store::is_terminal(run.state);
      const bool quiet = std::chrono::steady_clock::now() - last_write >= slot.heartbeat_interval();
      if (finished || quiet) {  // the final state, after the last evaluation; or a heartbeat
        if (!send(nullptr, !finished))
          return grpc::Status(grpc::StatusCode::CANCELLED, "client gone");
      }
    }
    return grpc::Status::OK;
  });
}

grpc::Status TrainingServiceImpl::GetRunMetrics(grpc::ServerContext*,
                                                const GetRunMetricsRequest* request,
                                                GetRunMetricsResponse* response) {
  return guarded([&] {
    for (const auto& p : manager_.metrics(require_run_id(request->run_id())))
      to_proto(p, *response->add_points());
    return grpc::Status::OK;
  });
}

grpc::Status TrainingServiceImpl::ListCheckpoints(grpc::ServerContext*,
                                                  const ListCheckpointsRequest* request,
                                                  ListCheckpointsResponse* response) {
  return guarded([&] {
    for (const auto& c : manager_.checkpoints(require_run_id(request->run_id())))
      to_proto(c, *response->add_checkpoints());
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
