#include "services/store/store_convert.h"

#include <chrono>
#include <string>

#include "common/error.h"
#include "services/common/convert.h"

namespace pnp::services {

void to_proto(const store::RunSpec& spec, store_v1::RunSpec& out) {
  out.set_role(spec.role);
  out.set_algorithm(spec.algorithm);
  out.set_robot(spec.robot);
  out.set_object(spec.object);
  out.set_seed(spec.seed);
  out.set_config_json(spec.config_json);
  out.set_code_commit(spec.code_commit);
  if (spec.parent_checkpoint_id) out.set_parent_checkpoint_id(*spec.parent_checkpoint_id);
  out.set_gemm_path(spec.gemm_path);
}

store::RunSpec from_proto(const store_v1::RunSpec& spec) {
  store::RunSpec out;
  out.role = spec.role();
  out.algorithm = spec.algorithm();
  out.robot = spec.robot();
  out.object = spec.object();
  out.seed = spec.seed();
  out.config_json = spec.config_json();
  out.code_commit = spec.code_commit();
  if (spec.has_parent_checkpoint_id()) out.parent_checkpoint_id = spec.parent_checkpoint_id();
  out.gemm_path = spec.gemm_path();
  return out;
}

void to_proto(const store::RunRecord& run, store_v1::Run& out) {
  out.set_id(run.id);
  to_proto(run.spec, *out.mutable_spec());
  out.set_state(std::string(store::run_state_name(run.state)));
  out.set_created_ms(run.created_ms);
  out.set_updated_ms(run.updated_ms);
  if (run.finished_ms) out.set_finished_ms(*run.finished_ms);
  out.set_error(run.error);
  out.set_env_steps(run.env_steps);
  out.set_last_success(run.last_success);
  if (run.last_score) out.set_last_score(*run.last_score);
  out.set_reached(run.reached);
  if (run.steps_to_target) out.set_steps_to_target(*run.steps_to_target);
  out.set_owner(run.owner);
  if (run.lease_expires_ms) out.set_lease_expires_ms(*run.lease_expires_ms);
  services::to_proto(run.wall, *out.mutable_wall());
}

store::RunRecord from_proto(const store_v1::Run& run) {
  store::RunRecord out;
  out.id = run.id();
  out.spec = from_proto(run.spec());
  out.state = store::parse_run_state(run.state(), "run.state");
  out.created_ms = run.created_ms();
  out.updated_ms = run.updated_ms();
  if (run.has_finished_ms()) out.finished_ms = run.finished_ms();
  out.error = run.error();
  out.env_steps = run.env_steps();
  out.last_success = run.last_success();
  if (run.has_last_score()) out.last_score = run.last_score();
  out.reached = run.reached();
  if (run.has_steps_to_target()) out.steps_to_target = run.steps_to_target();
  out.owner = run.owner();
  if (run.has_lease_expires_ms()) out.lease_expires_ms = run.lease_expires_ms();
  out.wall = services::from_proto(run.wall());
  return out;
}

void to_proto(const store::MetricPoint& point, store_v1::MetricPoint& out) {
  out.set_env_steps(point.env_steps);
  out.set_episodes(point.episodes);
  out.set_wall_s(point.wall_s);
  out.set_task_success(point.task_success);
  out.set_subtask_success(point.subtask_success);
  out.set_sampled_success(point.sampled_success);
  out.set_critic_loss(point.critic_loss);
  out.set_actor_loss(point.actor_loss);
  out.set_updates(point.updates);
  if (point.stop_score) out.set_stop_score(*point.stop_score);
}

store::MetricPoint from_proto(const store_v1::MetricPoint& point) {
  store::MetricPoint out;
  out.env_steps = point.env_steps();
  out.episodes = point.episodes();
  out.wall_s = point.wall_s();
  out.task_success = point.task_success();
  out.subtask_success = point.subtask_success();
  out.sampled_success = point.sampled_success();
  out.critic_loss = point.critic_loss();
  out.actor_loss = point.actor_loss();
  out.updates = point.updates();
  if (point.has_stop_score()) out.stop_score = point.stop_score();
  return out;
}

void to_proto(const store::TrainerCounters& counters, store_v1::TrainerCounters& out) {
  out.set_episodes(counters.episodes);
  out.set_updates(counters.updates);
  out.set_wall_s(counters.wall_s);
  out.set_eval_wall_s(counters.eval_wall_s);
}

store::TrainerCounters from_proto(const store_v1::TrainerCounters& counters) {
  return {counters.episodes(), counters.updates(), counters.wall_s(), counters.eval_wall_s()};
}

void to_proto(const store::CheckpointInfo& info, store_v1::CheckpointInfo& out) {
  out.set_id(info.id);
  out.set_run_id(info.run_id);
  out.set_role(info.role);
  out.set_env_steps(info.env_steps);
  out.set_eval_success(info.eval_success);
  out.set_checksum(info.checksum);
  out.set_size_bytes(info.size_bytes);
  out.set_created_ms(info.created_ms);
  if (info.unevaluated) to_proto(*info.unevaluated, *out.mutable_unevaluated());
}

store::CheckpointInfo from_proto(const store_v1::CheckpointInfo& info) {
  store::CheckpointInfo out;
  out.id = info.id();
  out.run_id = info.run_id();
  out.role = info.role();
  out.env_steps = info.env_steps();
  out.eval_success = info.eval_success();
  out.checksum = info.checksum();
  out.size_bytes = info.size_bytes();
  out.created_ms = info.created_ms();
  if (info.has_unevaluated()) out.unevaluated = from_proto(info.unevaluated());
  return out;
}

void to_proto(const store::Promotion& promotion, store_v1::Promotion& out) {
  out.set_role(promotion.role);
  out.set_checkpoint_id(promotion.checkpoint_id);
  out.set_promoted_ms(promotion.promoted_ms);
  out.set_promoted_by(promotion.promoted_by);
}

store::Promotion from_proto(const store_v1::Promotion& promotion) {
  return {promotion.role(), promotion.checkpoint_id(), promotion.promoted_ms(),
          promotion.promoted_by()};
}

void to_proto(const store::GcReport& report, store_v1::GcReport& out) {
  out.set_checkpoints_deleted(report.checkpoints_deleted);
  out.set_bytes_deleted(report.bytes_deleted);
  out.set_pages_freed(report.pages_freed);
}

store::GcReport from_proto(const store_v1::GcReport& report) {
  return {report.checkpoints_deleted(), report.bytes_deleted(), report.pages_freed()};
}

store::RunFilter from_proto(const store_v1::ListRunsRequest& request) {
  store::RunFilter filter;
  if (request.has_role()) filter.role = request.role();
  if (request.has_state()) filter.state = store::parse_run_state(request.state(), "state");
  filter.limit = request.limit();
  filter.before_id = request.before_id();
  return filter;
}

void to_proto(const store::RunFilter& filter, store_v1::ListRunsRequest& out) {
  if (filter.role) out.set_role(*filter.role);
  if (filter.state) out.set_state(std::string(store::run_state_name(*filter.state)));
  out.set_limit(filter.limit);
  out.set_before_id(filter.before_id);
}

std::chrono::milliseconds lease_from_proto(std::int64_t lease_ms, std::string_view field) {
  constexpr std::int64_t kDay_ms = 24LL * 3600 * 1000;
  if (lease_ms <= 0 || lease_ms > kDay_ms) {
    throw_invalid_argument(std::string(field), "a lease of 1 ms to a day, in ms",
                           std::to_string(lease_ms));
  }
  return std::chrono::milliseconds(lease_ms);
}

store::RetentionPolicy retention_from_proto(std::int32_t keep_last, std::string_view field) {
  if (keep_last < 1) {
    throw_invalid_argument(std::string(field), "at least 1", std::to_string(keep_last));
  }
  return {.keep_last = keep_last};
}

void to_proto(const store::AuditRecord& record, store_v1::AuditEntry& out) {
  out.set_id(record.id);
  out.set_ts_ms(record.ts_ms);
  out.set_service(record.service);
  out.set_principal(record.principal);
  out.set_peer(record.peer);
  out.set_rpc(record.rpc);
  out.set_request(record.request);
  out.set_code(record.code);
  out.set_recorded_by(record.recorded_by);
  out.set_received_ms(record.received_ms);
}

store::AuditRecord from_proto(const store_v1::AuditEntry& entry) {
  // recorded_by and received_ms are the store's to set, never the sender's.
  return {entry.id(),   entry.ts_ms(), entry.service(), entry.principal(),
          entry.peer(), entry.rpc(),   entry.request(), entry.code()};
}

}  // namespace pnp::services
