#include "rl/network_limits.h"

#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp::rl {

void check_layer_widths(std::string_view field, std::span<const int> widths, int inputs,
                        int outputs) {
  const std::string name(field);
  if (widths.empty() || widths.size() > static_cast<std::size_t>(kMaxHiddenLayers)) {
    throw_invalid_argument(name, "1 to " + std::to_string(kMaxHiddenLayers) + " hidden layers",
                           std::to_string(widths.size()));
  }
  long long parameters = 0;
  long long previous = inputs;
  for (std::size_t i = 0; i < widths.size(); ++i) {
    if (widths[i] <= 0 || widths[i] > kMaxLayerWidth) {
      throw_invalid_argument(name + "[" + std::to_string(i) + "]",
                             "a width from 1 to " + std::to_string(kMaxLayerWidth),
                             std::to_string(widths[i]));
    }
    parameters += (previous + 1) * widths[i];
    previous = widths[i];
  }
  parameters += (previous + 1) * outputs;
  if (parameters > kMaxNetworkParameters) {
    throw_invalid_argument(
        name, "a network of at most " + std::to_string(kMaxNetworkParameters) + " parameters",
        std::to_string(parameters) + " parameters");
  }
}

void check_chain_prior(std::string_view field, double chain_prior) {
  if (!(std::abs(chain_prior) <= kMaxChainPrior)) {
    const std::string bound = std::to_string(static_cast<int>(kMaxChainPrior));
    throw_invalid_argument(field, "a logit bonus from -" + bound + " to " + bound,
                           std::to_string(chain_prior));
  }
}

}  // namespace pnp::rl
