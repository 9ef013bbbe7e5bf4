#pragma once
// Conversions between pnp.store.v1 messages and the store's records (store/records.h),
// used by both ends of the store service: what arrives is checked here (unknown states,
// negative sizes and lease times are INVALID_ARGUMENT naming the field); what the store
// itself validates (roles, limits, ownership) it refuses with its own errors.

#include <string_view>

#include "pnp/store/v1/store_service.pb.h"
#include "store/records.h"
#include "store/store.h"

namespace pnp::services {

namespace store_v1 = ::pnp::store::v1;

void to_proto(const store::RunSpec& spec, store_v1::RunSpec& out);
store::RunSpec from_proto(const store_v1::RunSpec& spec);
void to_proto(const store::RunRecord& run, store_v1::Run& out);
store::RunRecord from_proto(const store_v1::Run& run);
void to_proto(const store::MetricPoint& point, store_v1::MetricPoint& out);
store::MetricPoint from_proto(const store_v1::MetricPoint& point);
void to_proto(const store::TrainerCounters& counters, store_v1::TrainerCounters& out);
store::TrainerCounters from_proto(const store_v1::TrainerCounters& counters);
void to_proto(const store::CheckpointInfo& info, store_v1::CheckpointInfo& out);
store::CheckpointInfo from_proto(const store_v1::CheckpointInfo& info);
void to_proto(const store::Promotion& promotion, store_v1::Promotion& out);
store::Promotion from_proto(const store_v1::Promotion& promotion);
void to_proto(const store::GcReport& report, store_v1::GcReport& out);
store::GcReport from_proto(const store_v1::GcReport& report);
void to_proto(const store::AuditRecord& record, store_v1::AuditEntry& out);
store::AuditRecord from_proto(const store_v1::AuditEntry& entry);

store::RunFilter from_proto(const store_v1::ListRunsRequest& request);
void to_proto(const store::RunFilter& filter, store_v1::ListRunsRequest& out);

// A lease of `lease_ms` milliseconds: positive, at most a day.
std::chrono::milliseconds lease_from_proto(std::int64_t lease_ms, std::string_view field);
// keep_last: at least 1.
store::RetentionPolicy retention_from_proto(std::int32_t keep_last, std::string_view field);

}  // namespace pnp::services
