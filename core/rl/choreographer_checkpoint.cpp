#include "rl/choreographer_checkpoint.h"

#include <nlohmann/json.hpp>

#include "common/error.h"
#include "nn/checkpoint_io.h"
#include "nn/flat_ops.h"
#include "rl/checkpoint_sections.h"
#include "rl/network_limits.h"

namespace pnp::rl {
namespace {

constexpr const char* kKind = "choreographer";

std::string block_name(std::size_t index) {
  return "block" + std::to_string(index);
}

}  // namespace

std::vector<std::uint8_t> save_choreographer(const ChoreographerMeta& meta, ChoreographerNet& net) {
  nlohmann::json j = {{"kind", kKind},
                      {"trunk", meta.network.trunk},
                      {"lstm", meta.network.lstm},
                      {"predicate_inputs", meta.network.predicate_inputs},
                      {"mask_finished", meta.network.mask_finished},
                      {"chain_prior", meta.network.chain_prior}};
  write_provenance(meta, j);
  nn::CheckpointWriter w;
  write_meta(w, j);
  const auto blocks = net.parameter_blocks();
  for (std::size_t b = 0; b < blocks.size(); ++b) w.add_floats(block_name(b), blocks[b]);
  write_normalizer(w, "norm", net.normalizer());
  return w.finish();
}

LoadedChoreographer load_choreographer(std::span<const std::uint8_t> bytes) {
  const nn::CheckpointReader r(bytes);
  const nlohmann::json j = read_meta(r, kKind);
  ChoreographerMeta meta = parse_meta(j, [](const nlohmann::json& m) {
    ChoreographerMeta out;
    read_provenance(m, out);
    out.network.trunk = m.at("trunk").get<std::vector<int>>();
    out.network.lstm = m.at("lstm");
    // Checkpoints written before these became options had both.
    out.network.predicate_inputs = m.value("predicate_inputs", true);
    out.network.mask_finished = m.value("mask_finished", true);
    out.network.chain_prior = m.value("chain_prior", 0.0);  // none before it existed
    return out;
  });
  if (meta.network.trunk.empty() || meta.network.lstm <= 0) {
    throw_invalid_argument("checkpoint network", "a trunk and a positive LSTM width",
                           "an empty network");
  }
  // Bounded before anything is allocated: the file's own metadata sizes the network.
  meta.network.validate("checkpoint ");
  ChoreographerNet net(meta.network);
  auto blocks = net.parameter_blocks();
  for (std::size_t b = 0; b < blocks.size(); ++b)
    nn::copy_into(blocks[b], r.floats(block_name(b), blocks[b].size()));
  read_normalizer(r, "norm", net.normalizer());
  return {std::move(meta), std::move(net)};
}

}  // namespace pnp::rl
