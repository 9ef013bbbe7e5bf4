// The choreographer checkpoint loader on arbitrary bytes.
#include <cstddef>
#include <cstdint>
#include <span>

#include "rl/choreographer_checkpoint.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pnp::fuzz::refuse_or_accept([&] { pnp::rl::load_choreographer(std::span(data, size)); });
  return 0;
}
