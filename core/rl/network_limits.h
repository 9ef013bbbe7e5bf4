#pragma once
// What one training request may ask of a server: layer widths, depth, parameters per
// network, batch size and A3C workers. Generous beyond anything this method uses (the
// paper's experts are 3 x 256, about 150k parameters; batches of 256; 2 to 8 workers),
// tight enough that one request cannot take a server's memory or threads (a fuzzed
// request asking for two layers of a million units did).

#include <span>
#include <string_view>

namespace pnp::rl {

inline constexpr int kMaxHiddenLayers = 8;
inline constexpr int kMaxLayerWidth = 4096;
inline constexpr long long kMaxNetworkParameters = 4'000'000;
inline constexpr int kMaxLstmWidth = 1000;  // its 4 x width^2 recurrent weights fit the bound
inline constexpr int kMaxBatchSize = 4096;
inline constexpr int kMaxA3cWorkers = 64;
// The choreographer's chain prior, a logit bonus: beyond this it is a fixed plan.
inline constexpr double kMaxChainPrior = 20.0;

// INVALID_ARGUMENT naming `field` (or `field[i]`) unless there are 1 to kMaxHiddenLayers
// widths, each 1 to kMaxLayerWidth, and the network from `inputs` through them to
// `outputs` has at most kMaxNetworkParameters weights and biases.
void check_layer_widths(std::string_view field, std::span<const int> widths, int inputs,
                        int outputs);

// INVALID_ARGUMENT naming `field` unless the chain prior is within +-kMaxChainPrior (NaN
// is refused).
void check_chain_prior(std::string_view field, double chain_prior);

}  // namespace pnp::rl
