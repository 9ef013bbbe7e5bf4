#pragma once
// Parsing names into enums, with one error format for all: "robot: expected one of
// fetch, panda, got "ur5"". The list of accepted names comes from the enum's own
// to-name function, so it cannot drift from the values.

#include <span>
#include <string>
#include <string_view>

#include "common/error.h"

namespace pnp {

template <typename Enum>
Enum parse_enum(std::string_view name, std::span<const Enum> values,
                std::string_view (*to_name)(Enum), std::string_view field) {
  std::string expected = "one of ";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (to_name(values[i]) == name) return values[i];
    expected.append(i ? ", " : "").append(to_name(values[i]));
  }
  throw_invalid_argument(field, expected, "\"" + std::string(name) + "\"");
}

}  // namespace pnp
