#include "rl/gae.h"

#include "common/error.h"

namespace pnp::rl {

Advantages compute_gae(std::span<const double> rewards, std::span<const double> values,
                       double bootstrap_value, std::span<const double> discounts, double lambda) {
  if (rewards.size() != values.size() || rewards.size() != discounts.size())
    throw_internal("compute_gae: rewards, values and discounts differ in length");
  Advantages out;
  out.advantages.assign(rewards.size(), 0.0);
  out.returns.assign(rewards.size(), 0.0);
  double next_value = bootstrap_value, running = 0.0;
  for (std::size_t t = rewards.size(); t-- > 0;) {
    const double delta = rewards[t] + discounts[t] * next_value - values[t];
    running = delta + discounts[t] * lambda * running;
    out.advantages[t] = running;
    out.returns[t] = running + values[t];
    next_value = values[t];
  }
  return out;
}

Advantages compute_gae(std::span<const double> rewards, std::span<const double> values,
                       double bootstrap_value, double gamma, double lambda) {
  const std::vector<double> discounts(rewards.size(), gamma);
  return compute_gae(rewards, values, bootstrap_value, discounts, lambda);
}

}  // namespace pnp::rl
