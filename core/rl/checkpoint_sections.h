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

// What every policy checkpoint records beside its network: the world it trained in (robot,
// object, profile, actuation) and its provenance (steps, evaluated success, seed, commit,
// GEMM path). Written and read here only, so the two kinds cannot drift apart. A field
// missing from an older file keeps `out`'s default (its Meta type says what files before
// the field held).
template <typename Meta>
void write_provenance(const Meta& meta, nlohmann::json& j) {
  j["robot"] = meta.robot;
  j["object"] = meta.object;
  j["world"] = meta.world;
  j["actuation"] = meta.actuation;
  j["train_env_steps"] = meta.train_env_steps;
  j["eval_success"] = meta.eval_success;
  j["seed"] = meta.seed;
  j["code_commit"] = meta.code_commit;
  j["gemm_path"] = meta.gemm_path;
}
template <typename Meta>
void read_provenance(const nlohmann::json& m, Meta& out) {
  out.robot = m.at("robot");
  out.object = m.at("object");
  out.world = m.value("world", out.world);
  out.actuation = m.value("actuation", out.actuation);
  out.train_env_steps = m.at("train_env_steps");
  out.eval_success = m.at("eval_success");
  out.seed = m.at("seed");
  out.code_commit = m.value("code_commit", out.code_commit);
  out.gemm_path = m.value("gemm_path", out.gemm_path);
}

// DATA_LOSS unless section `name` holds exactly `count` floats: checked before the network
// it fills is allocated.
void require_float_section(const nn::CheckpointReader& r, const std::string& name,
                           std::size_t count);

void write_normalizer(nn::CheckpointWriter& w, const std::string& name, const nn::Normalizer& n);
// Restores `n` (already of the right size and clip) from the sections written above.
void read_normalizer(const nn::CheckpointReader& r, const std::string& name, nn::Normalizer& n);

}  // namespace pnp::rl
