#pragma once
// The q-quantile of a sample (nearest rank below, q in [0, 1]; 0 for an empty sample),
// as every latency figure the benchmarks and the gateway report it.

#include <algorithm>
#include <vector>

namespace pnp {

inline double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace pnp
