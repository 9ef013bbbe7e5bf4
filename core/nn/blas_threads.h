#pragma once
// OpenBLAS's threaded GEMM gives results that depend on its thread count (measured: the
// same 50 DDPG updates end in different weights at 1 and 2 threads). The project's
// results must not, so OpenBLAS is pinned to one thread; parallelism is the project's
// own, with fixed partitions.

namespace pnp::nn {

// Idempotent and thread-safe; called by every network constructor.
void pin_blas_to_one_thread();

}  // namespace pnp::nn
