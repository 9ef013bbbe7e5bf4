#pragma once
// Sections shared by every policy checkpoint (experts, the choreographer): the JSON
// metadata with its "kind", and a normaliser's running statistics.

#include <nlohmann/json.hpp>
#include <string>

#include "common/error.h"
#include "nn/checkpoint_io.h"
#include "nn/normalizer.h"

namespace pnp::rl {

// Writes the metadata section; `meta` must hold "kind".
void write_meta(nn::CheckpointWriter& w, const nlohmann::json& meta);
// Reads the metadata section: DATA_LOSS if unreadable, INVALID_ARGUMENT if its kind is
// not `kind` (an intact file of something else).
nlohmann::json read_meta(const nn::CheckpointReader& r, const std::string& kind);
// Runs `parse` on the metadata; a missing or mistyped field is DATA_LOSS.
template <typename Parse>
auto parse_meta(const nlohmann::json& j, Parse parse) {
  try {
    return parse(j);
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::kDataLoss, std::string("checkpoint: incomplete metadata: ") + e.what());
  }
}

// DATA_LOSS unless section `name` holds exactly `count` floats: checked before the network
// it fills is allocated.
void require_float_section(const nn::CheckpointReader& r, const std::string& name,
                           std::size_t count);

void write_normalizer(nn::CheckpointWriter& w, const std::string& name, const nn::Normalizer& n);
// Restores `n` (already of the right size and clip) from the sections written above.
void read_normalizer(const nn::CheckpointReader& r, const std::string& name, nn::Normalizer& n);

}  // namespace pnp::rl
