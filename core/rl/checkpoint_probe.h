#pragma once
// A checkpoint checked as a replica would serve it, before a promotion commits: every
// replica loads what is promoted, again at each restart, so a file that passes the
// store's checksum but not this would take the whole inference tier down.

#include <cstdint>
#include <span>
#include <string_view>

namespace pnp::rl {

// Parses `bytes` as the checkpoint `role` serves from (an expert of that role for
// approach, manipulate, retract and e2e; the choreographer for hlc) within the bounds of
// rl/network_limits.h, and runs its networks once on a probe input. Errors name `field`
// and keep their code: INVALID_ARGUMENT for a checkpoint of another role, bounds exceeded
// or a non-finite output (weights or statistics that are not numbers); DATA_LOSS for
// bytes that do not parse.
void probe_checkpoint(std::string_view role, std::span<const std::uint8_t> bytes,
                      std::string_view field);

}  // namespace pnp::rl
