// The kernel on AVX2 with FMA: 16-row panels (two 8-float registers down a column of A)
// times blocks of up to 6 columns, every accumulator in a register; B is read in place and
// A's panels are copied to the stack first (pack_panel says why). Compiled for
// AVX2+FMA whatever the build's -march; run only where the CPU has them
// (nn/direct_gemm.cpp). Element by element the same arithmetic as the AVX-512 kernel, so
// the two give the same bits.

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <utility>

#include "nn/direct_gemm_kernels.h"

// Everything after this line is compiled for AVX2+FMA (headers above keep the build's
// target, so no library code is emitted with instructions the CPU may lack).
#define PNP_TARGET "avx2,fma"
#include "nn/target_begin.h"

namespace pnp::nn::avx2 {
namespace {

constexpr std::ptrdiff_t kPanelRows = 16;  // two 8-float registers down a column of A
constexpr std::size_t kMaxBlockCols = 6;   // 12 accumulators + 2 A loads + 1 broadcast of 16

// Lanes below `rows` of the panel's low and high register (AVX2 masks are vectors).
struct RowMasks {
  __m256i low, high;
};

RowMasks row_masks(std::ptrdiff_t rows) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const auto r = static_cast<int>(rows);
  return {_mm256_cmpgt_epi32(_mm256_set1_epi32(r), lane),
          _mm256_cmpgt_epi32(_mm256_set1_epi32(r - 8), lane)};
}

// A full panel loads and stores whole registers; a partial one (the last rows of A or C)
// masks, reading and writing nothing past the matrix. Masked stores are slow on AMD, so
// they are kept to the tail.
template <bool Full>
__m256 load(const float* p, __m256i mask) {
  if constexpr (Full)
    return _mm256_loadu_ps(p);
  else
    return _mm256_maskload_ps(p, mask);
}

template <bool Full>
void store(float* p, __m256i mask, __m256 v) {
  if constexpr (Full)
    _mm256_storeu_ps(p, v);
  else
    _mm256_maskstore_ps(p, mask, v);
}

// What happens to a block's sums as they are stored.
struct Epilogue {
  RowMasks rows;
  bool accumulate;
  __m256 bias_low, bias_high;  // zero when there is no bias
  bool relu;
  const float* relu_output;  // at this block's first element, leading dimension ldc
};

// C[16 x Cols] (+)= A[16 x k] B[k x Cols]: every accumulator stays in a register.
template <std::size_t Cols, bool Full>
void block(std::ptrdiff_t k, const float* a, std::ptrdiff_t lda, const float* b,
           std::ptrdiff_t b_row, std::ptrdiff_t b_col, float* c, std::ptrdiff_t ldc,
           const Epilogue& e) {
  __m256 low[Cols], high[Cols];  // NOLINT: registers, not storage
#pragma GCC unroll 8
  for (std::size_t j = 0; j < Cols; ++j) low[j] = high[j] = _mm256_setzero_ps();
  for (std::ptrdiff_t p = 0; p < k; ++p) {
    const __m256 a_low = load<Full>(a + p * lda, e.rows.low);
    const __m256 a_high = load<Full>(a + p * lda + 8, e.rows.high);
    const float* bp = b + p * b_row;
#pragma GCC unroll 8
    for (std::size_t j = 0; j < Cols; ++j) {
      const __m256 bj = _mm256_broadcast_ss(bp + static_cast<std::ptrdiff_t>(j) * b_col);
      low[j] = _mm256_fmadd_ps(a_low, bj, low[j]);
      high[j] = _mm256_fmadd_ps(a_high, bj, high[j]);
    }
  }
  const __m256 zero = _mm256_setzero_ps();
#pragma GCC unroll 8
  for (std::size_t j = 0; j < Cols; ++j) {
    float* cj = c + static_cast<std::ptrdiff_t>(j) * ldc;
    __m256 add_low = e.bias_low, add_high = e.bias_high;
    if (e.accumulate) {
      add_low = load<Full>(cj, e.rows.low);
      add_high = load<Full>(cj + 8, e.rows.high);
    }
    low[j] = _mm256_add_ps(add_low, low[j]);
    high[j] = _mm256_add_ps(add_high, high[j]);
    if (e.relu) {  // max_ps returns its second operand for NaN: NaN stays NaN, as in Eigen
      low[j] = _mm256_max_ps(zero, low[j]);
      high[j] = _mm256_max_ps(zero, high[j]);
    }
    if (e.relu_output) {
      const float* out = e.relu_output + static_cast<std::ptrdiff_t>(j) * ldc;
      const __m256 out_low = load<Full>(out, e.rows.low);
      const __m256 out_high = load<Full>(out + 8, e.rows.high);
      low[j] = _mm256_and_ps(_mm256_cmp_ps(out_low, zero, _CMP_GT_OQ), low[j]);
      high[j] = _mm256_and_ps(_mm256_cmp_ps(out_high, zero, _CMP_GT_OQ), high[j]);
    }
    store<Full>(cj, e.rows.low, low[j]);
    store<Full>(cj + 8, e.rows.high, high[j]);
  }
}

// A's row panels up to this depth are copied, contiguous, into a buffer on the stack
// (32 KiB) before use; deeper products read A in place.
constexpr std::ptrdiff_t kMaxPackedDepth = 512;

Epilogue epilogue(const DirectGemmOperands& op, std::ptrdiff_t i, std::ptrdiff_t j,
                  std::ptrdiff_t rows) {
  Epilogue e{.rows = row_masks(rows),
             .accumulate = op.accumulate,
             .bias_low = _mm256_setzero_ps(),
             .bias_high = _mm256_setzero_ps(),
             .relu = op.relu,
             .relu_output = op.relu_output ? op.relu_output + j * op.m + i : nullptr};
  if (op.row_bias) {
    e.bias_low = _mm256_maskload_ps(op.row_bias + i, e.rows.low);
    e.bias_high = _mm256_maskload_ps(op.row_bias + i + 8, e.rows.high);
  }
  return e;
}

// C's rows [i, i + rows) of the Cols columns from j, with A's panel at `a` (leading
// dimension lda: op.m in place, kPanelRows packed).
template <std::size_t Cols, bool Full>
void run_block(const DirectGemmOperands& op, const float* a, std::ptrdiff_t lda, std::ptrdiff_t i,
               std::ptrdiff_t j, std::ptrdiff_t rows) {
  block<Cols, Full>(op.k, a, lda, op.b + j * op.b_col_stride, op.b_row_stride, op.b_col_stride,
                    op.c + j * op.m + i, op.m, epilogue(op, i, j, rows));
}

// One block of Cols columns for C's rows from i0 on, A read in place (a B block stays in L1
// across the row panels).
template <std::size_t Cols>
void column_block(const DirectGemmOperands& op, std::ptrdiff_t j, std::ptrdiff_t i0) {
  for (std::ptrdiff_t i = i0; i < op.m; i += kPanelRows) {
    const std::ptrdiff_t rows = std::min(kPanelRows, op.m - i);
    if (rows == kPanelRows)
      run_block<Cols, true>(op, op.a + i, op.m, i, j, rows);
    else
      run_block<Cols, false>(op, op.a + i, op.m, i, j, rows);
  }
}

// One block of Cols columns for the full row panel at i, copied to `panel`.
template <std::size_t Cols>
void packed_block(const DirectGemmOperands& op, const float* panel, std::ptrdiff_t i,
                  std::ptrdiff_t j) {
  run_block<Cols, true>(op, panel, kPanelRows, i, j, kPanelRows);
}

// A's 16 rows from i, k columns, to 16 contiguous floats per k step. Read in place, a
// panel's k steps lie a whole column of A apart (1 KiB for 256 rows): a new 4 KiB page
// every 4 steps, which the prefetchers do not follow, and few cache sets. Packed, the
// kernel reached OpenBLAS's speed on an AMD EPYC (Zen 3): 87-89 against 72-78 GFLOP/s
// for 256 x 256 x 256. The copy moves values only: no bit changes.
void pack_panel(const float* a, std::ptrdiff_t lda, std::ptrdiff_t k, float* panel) {
  for (std::ptrdiff_t p = 0; p < k; ++p) {
    _mm256_store_ps(panel + p * kPanelRows, _mm256_loadu_ps(a + p * lda));
    _mm256_store_ps(panel + p * kPanelRows + 8, _mm256_loadu_ps(a + p * lda + 8));
  }
}

using ColumnBlockFn = void (*)(const DirectGemmOperands&, std::ptrdiff_t, std::ptrdiff_t);
using PackedBlockFn = void (*)(const DirectGemmOperands&, const float*, std::ptrdiff_t,
                               std::ptrdiff_t);

template <std::size_t... I>
constexpr std::array<ColumnBlockFn, sizeof...(I)> column_blocks(std::index_sequence<I...>) {
  return {&column_block<I + 1>...};
}

template <std::size_t... I>
constexpr std::array<PackedBlockFn, sizeof...(I)> packed_blocks(std::index_sequence<I...>) {
  return {&packed_block<I + 1>...};
}

// k...Blocks[w - 1] handles a block w columns wide.
constexpr auto kColumnBlocks = column_blocks(std::make_index_sequence<kMaxBlockCols>{});
constexpr auto kPackedBlocks = packed_blocks(std::make_index_sequence<kMaxBlockCols>{});

// One whole 8 x 8 tile: 8 source columns of 8 rows, transposed by unpacking pairs,
// shuffling pairs of pairs and swapping 128-bit halves, with no trip through memory.
void transpose_tile(const float* src, std::ptrdiff_t lds, float* dst, std::ptrdiff_t ldd) {
  __m256 r[8], t[8];  // NOLINT: registers, not storage
  for (int c = 0; c < 8; ++c) r[c] = _mm256_loadu_ps(src + c * lds);
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = _mm256_unpacklo_ps(r[2 * i], r[2 * i + 1]);
    t[2 * i + 1] = _mm256_unpackhi_ps(r[2 * i], r[2 * i + 1]);
  }
  for (int i = 0; i < 2; ++i) {
    r[4 * i + 0] = _mm256_shuffle_ps(t[4 * i + 0], t[4 * i + 2], _MM_SHUFFLE(1, 0, 1, 0));
    r[4 * i + 1] = _mm256_shuffle_ps(t[4 * i + 0], t[4 * i + 2], _MM_SHUFFLE(3, 2, 3, 2));
    r[4 * i + 2] = _mm256_shuffle_ps(t[4 * i + 1], t[4 * i + 3], _MM_SHUFFLE(1, 0, 1, 0));
    r[4 * i + 3] = _mm256_shuffle_ps(t[4 * i + 1], t[4 * i + 3], _MM_SHUFFLE(3, 2, 3, 2));
  }
  for (int q = 0; q < 4; ++q) {
    t[q] = _mm256_permute2f128_ps(r[q], r[4 + q], 0x20);
    t[q + 4] = _mm256_permute2f128_ps(r[q], r[4 + q], 0x31);
  }
  // t[x] is source row x: destination column x.
  for (int x = 0; x < 8; ++x) _mm256_storeu_ps(dst + x * ldd, t[x]);
}

// A partial tile at the matrix's edge, element by element.
void transpose_edge(const float* src, std::ptrdiff_t lds, std::ptrdiff_t tile_rows,
                    std::ptrdiff_t tile_cols, float* dst, std::ptrdiff_t ldd) {
  for (std::ptrdiff_t x = 0; x < tile_rows; ++x)
    for (std::ptrdiff_t c = 0; c < tile_cols; ++c) dst[c + x * ldd] = src[x + c * lds];
}

}  // namespace

void transpose(const float* src, std::ptrdiff_t rows, std::ptrdiff_t cols, float* dst) {
  for (std::ptrdiff_t r0 = 0; r0 < rows; r0 += 8) {
    for (std::ptrdiff_t c0 = 0; c0 < cols; c0 += 8) {
      const float* s = src + r0 + c0 * rows;
      float* d = dst + c0 + r0 * cols;
      if (rows - r0 >= 8 && cols - c0 >= 8)
        transpose_tile(s, rows, d, cols);
      else
        transpose_edge(s, rows, std::min<std::ptrdiff_t>(8, rows - r0),
                       std::min<std::ptrdiff_t>(8, cols - c0), d, cols);
    }
  }
}

void gemm(const DirectGemmOperands& op) {
  constexpr auto kMax = static_cast<std::ptrdiff_t>(kMaxBlockCols);
  // Full row panels outermost, each copied once and reused by every column block; the
  // last partial panel, and products too deep to copy, read A in place.
  std::ptrdiff_t in_place_from = 0;
  if (op.k <= kMaxPackedDepth) {
    alignas(32) float panel[kMaxPackedDepth * kPanelRows];  // NOLINT: scratch, not state
    in_place_from = op.m / kPanelRows * kPanelRows;
    for (std::ptrdiff_t i = 0; i < in_place_from; i += kPanelRows) {
      pack_panel(op.a + i, op.m, op.k, panel);
      for (std::ptrdiff_t j = 0; j < op.n; j += kMax) {
        const auto width = static_cast<std::size_t>(std::min(kMax, op.n - j));
        kPackedBlocks[width - 1](op, panel, i, j);
      }
    }
  }
  if (in_place_from == op.m) return;
  for (std::ptrdiff_t j = 0; j < op.n; j += kMax) {
    const auto width = static_cast<std::size_t>(std::min(kMax, op.n - j));
    kColumnBlocks[width - 1](op, j, in_place_from);
  }
}

}  // namespace pnp::nn::avx2

#include "nn/target_end.h"
