#include "rl/gae.h"

#include "common/error.h"

namespace pnp::rl {

Advantages compute_gae(std::span<const double> rewards, std::span<const double> values,
                       double bootstrap_value, double gamma, double lambda) {
  if (rewards.size() != values.size())
    throw_internal("compute_gae: rewards and values differ in length");
  Advantages out;
  out.advantages.assign(rewards.size(), 0.0);
  out.returns.assign(rewards.size(), 0.0);
  double next_value = bootstrap_value, running = 0.0;
  for (std::size_t t = rewards.size(); t-- > 0;) {
    const double delta = rewards[t] + gamma * next_value - values[t];
    running = delta + gamma * lambda * running;
    out.advantages[t] = running;
    out.returns[t] = running + values[t];
    next_value = values[t];
  }
  return out;
}

}  // namespace pnp::rl
