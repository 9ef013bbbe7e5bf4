#pragma once
// Unguessable identifiers: a lease id is the capability to drive the arm, so it comes from
// the kernel's random source (getrandom), never from a counter, a clock or a seeded Rng.

#include <string>

namespace pnp {

// `bytes` random bytes (1 to 64) as lowercase hex; INTERNAL if the kernel cannot supply
// them.
std::string secret_token_hex(int bytes = 16);

}  // namespace pnp
