#pragma once
// Boundary checks shared by every entry point: a vector input must have the expected
// size and only finite values. Errors name the field (and the index) and what was
// expected, e.g. "action[2]: expected a finite number, got nan".

#include <cstddef>
#include <span>
#include <string_view>

namespace pnp {

void require_size(std::size_t actual, std::size_t expected, std::string_view field);
void require_finite(std::span<const double> values, std::string_view field);
void require_finite_vector(std::span<const double> values, std::size_t expected_size,
                           std::string_view field);
void require_positive(long long value, std::string_view field);

}  // namespace pnp
