// The expert checkpoint loader on arbitrary bytes with a valid checksum (a file given to
// --init, imported or promoted), then the probe a promotion runs on it.
#include <cstddef>
#include <cstdint>
#include <span>

#include "rl/checkpoint_probe.h"
#include "rl/expert_checkpoint.h"
#include "tests/fuzz/checksummed_input.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = pnp::fuzz::with_valid_checksum(std::span(data, size));
  pnp::fuzz::refuse_or_accept([&] {
    const auto expert = pnp::rl::load_expert(file);
    pnp::rl::probe_checkpoint(expert.meta.role, file, "input");
  });
  return 0;
}
