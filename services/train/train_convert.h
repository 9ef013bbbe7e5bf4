#pragma once
// pnp.train.v1 messages <-> core/training and core/store values, validated at the
// boundary: unspecified or unknown enums and out-of-range values are INVALID_ARGUMENT
// naming the field.

#include <cstdint>
#include <string>

#include "pnp/train/v1/train_service.pb.h"
#include "store/records.h"
#include "training/run_manager.h"
#include "training/training_spec.h"

namespace pnp::services {

// The spec and checkpoint references of a create request (validated by the manager).
std::pair<training::TrainingSpec, training::CheckpointRefs> from_proto(
    const train::v1::CreateTrainingRunRequest& request);

std::string algorithm_name(train::v1::Algorithm algorithm, std::string_view field);
train::v1::Algorithm algorithm_from_name(std::string_view name);
train::v1::RunState to_proto(store::RunState state);
store::RunState from_proto(train::v1::RunState state, std::string_view field);
void to_proto(const store::MetricPoint& point, train::v1::MetricPoint& out);
void to_proto(const store::CheckpointInfo& info, train::v1::Checkpoint& out);
// ListTrainingRuns pages: the token is the last run id of the previous page (runs come
// newest first); empty reads 0, the first page. Anything else is INVALID_ARGUMENT naming
// page_token.
std::string page_token_after(std::int64_t last_run_id);
std::int64_t run_id_from_page_token(const std::string& token);
void set_millis(store::Millis ms, google::protobuf::Timestamp& out);

}  // namespace pnp::services
