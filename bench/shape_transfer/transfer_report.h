#pragma once
// The shape-transfer study's results as one JSON document and as a markdown table, one
// row per shape and one column per served policy.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/shape_transfer/transfer_training.h"

namespace pnp::bench {

// A column of the table: a served policy, named for the reader.
struct TransferColumn {
  std::string key;    // fine_tuned, fine_tuned_extra, block_hierarchy, e2e
  std::string title;  // "(a) hierarchy, retract fine-tuned", ...
};

nlohmann::json training_json(const std::vector<RoleTraining>& log);

// `cells[shape][column key]` holds play_gateway_cell's summaries (a missing one is "-");
// `fine_tuning[shape]` the shape's fine-tuning results (training_json).
std::string transfer_markdown(const std::vector<std::string>& shapes,
                              const std::vector<TransferColumn>& columns,
                              const nlohmann::json& cells, const nlohmann::json& fine_tuning);

}  // namespace pnp::bench
