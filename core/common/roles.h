#pragma once
// The roles of the platform's runs and checkpoints: the three subtask experts, the
// choreographer that sequences them, and the end-to-end baseline. Defined once: the store
// refuses any other, and an auth policy may bind a trainer's identity to some of them.

#include <algorithm>
#include <iterator>
#include <string_view>

namespace pnp {

inline constexpr std::string_view kRoles[] = {"approach", "manipulate", "retract", "hlc", "e2e"};

inline bool is_known_role(std::string_view role) {
  return std::find(std::begin(kRoles), std::end(kRoles), role) != std::end(kRoles);
}

}  // namespace pnp
