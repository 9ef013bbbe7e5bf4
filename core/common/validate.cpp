#include "common/validate.h"

#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp {

void require_size(std::size_t actual, std::size_t expected, std::string_view field) {
  if (actual != expected) {
    throw_invalid_argument(field, std::to_string(expected) + " values", std::to_string(actual));
  }
}

void require_finite(std::span<const double> values, std::string_view field) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw_invalid_argument(std::string(field) + "[" + std::to_string(i) + "]", "a finite number",
                             std::to_string(values[i]));
    }
  }
}

void require_finite_vector(std::span<const double> values, std::size_t expected_size,
                           std::string_view field) {
  require_size(values.size(), expected_size, field);
  require_finite(values, field);
}

void require_positive(long long value, std::string_view field) {
  if (value <= 0) throw_invalid_argument(field, "a positive integer", std::to_string(value));
}

}  // namespace pnp
