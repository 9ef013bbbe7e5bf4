#pragma once
// What one checkpoint, one run and one principal may hold in a store: its volume is shared
// by every trainer, and a trainer's identity (or whoever broke into its Pod) must not be
// able to fill it. pnp-store-server takes them as flags (--max-checkpoint-mb,
// --max-run-checkpoint-mb, --max-open-runs-per-principal); an embedded store uses the
// defaults. Refusals are RESOURCE_EXHAUSTED naming the quota.

#include <cstdint>

namespace pnp::store {

struct StoreQuotas {
  // One checkpoint. The largest the network bounds admit (rl/network_limits.h: an expert's
  // actor and critic, or a choreographer's LSTM and heads, of at most 4 M parameters each)
  // is about 50 MB; the platform's are a few MB.
  std::int64_t max_checkpoint_bytes = 64LL << 20;
  // All of one run's checkpoints together (a trainer keeps a few: --keep-checkpoints).
  std::int64_t max_run_checkpoint_bytes = 1LL << 30;
  // Pending or running runs one authenticated principal created and has not finished.
  int max_open_runs_per_principal = 64;
};

}  // namespace pnp::store
