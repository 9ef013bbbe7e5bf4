#pragma once
// Generalised advantage estimation (Schulman et al.): for rewards r_t, values V_t and
// the value after the last step (0 at a terminal state),
//   delta_t = r_t + gamma V_{t+1} - V_t,   A_t = sum_k (gamma lambda)^k delta_{t+k},
// and the value targets (returns) R_t = A_t + V_t.
//
// The semi-Markov form takes one discount per step instead of gamma: a choreographer
// decision whose expert ran k environment steps is discounted gamma^k, so a plan that
// wastes steps is worth less than one that does not (with a per-decision gamma a detour
// costs almost nothing, and the success at the last step is the same).

#include <span>
#include <vector>

namespace pnp::rl {

struct Advantages {
  std::vector<double> advantages;
  std::vector<double> returns;
};

Advantages compute_gae(std::span<const double> rewards, std::span<const double> values,
                       double bootstrap_value, double gamma, double lambda);

// discounts[t] multiplies the value after step t: delta_t = r_t + discounts[t] V_{t+1} - V_t,
// A_t = delta_t + discounts[t] lambda A_{t+1}.
Advantages compute_gae(std::span<const double> rewards, std::span<const double> values,
                       double bootstrap_value, std::span<const double> discounts, double lambda);

}  // namespace pnp::rl
