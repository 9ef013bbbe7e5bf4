#pragma once
// Generalised advantage estimation (Schulman et al.): for rewards r_t, values V_t and
// the value after the last step (0 at a terminal state),
//   delta_t = r_t + gamma V_{t+1} - V_t,   A_t = sum_k (gamma lambda)^k delta_{t+k},
// and the value targets (returns) R_t = A_t + V_t.

#include <span>
#include <vector>

namespace pnp::rl {

struct Advantages {
  std::vector<double> advantages;
  std::vector<double> returns;
};

Advantages compute_gae(std::span<const double> rewards, std::span<const double> values,
                       double bootstrap_value, double gamma, double lambda);

}  // namespace pnp::rl
