// The choreographer checkpoint loader on arbitrary bytes with a valid checksum, then the
// probe a promotion runs on it.
#include <cstddef>
#include <cstdint>
#include <span>

#include "rl/checkpoint_probe.h"
#include "rl/choreographer_checkpoint.h"
#include "tests/fuzz/checksummed_input.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = pnp::fuzz::with_valid_checksum(std::span(data, size));
  pnp::fuzz::refuse_or_accept([&] {
    pnp::rl::load_choreographer(file);
    pnp::rl::probe_checkpoint("hlc", file, "input");
  });
  return 0;
}
