// ListTrainingRuns page tokens, on arbitrary bytes: a token is refused only as
// INVALID_ARGUMENT naming page_token, and one that is accepted names a run id that makes
// the same token again (what the next page starts from cannot drift).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "services/train/train_convert.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string token(reinterpret_cast<const char*>(data), size);
  try {
    const std::int64_t id = pnp::services::run_id_from_page_token(token);
    const bool first_page = token.empty() && id == 0;
    if (!first_page && (id <= 0 || pnp::services::run_id_from_page_token(
                                       pnp::services::page_token_after(id)) != id)) {
      std::fprintf(stderr, "fuzz: page token accepted as run id %lld, which does not round-trip\n",
                   static_cast<long long>(id));
      std::abort();
    }
  } catch (const pnp::Error& e) {
    if (e.code() != pnp::ErrorCode::kInvalidArgument ||
        std::string(e.what()).find("page_token") == std::string::npos) {
      std::fprintf(stderr, "fuzz: page token refused without naming it: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
