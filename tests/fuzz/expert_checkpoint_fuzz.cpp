// The expert checkpoint loader on arbitrary bytes (a file given to --init or imported).
#include <cstddef>
#include <cstdint>
#include <span>

#include "rl/expert_checkpoint.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pnp::fuzz::refuse_or_accept([&] { pnp::rl::load_expert(std::span(data, size)); });
  return 0;
}
