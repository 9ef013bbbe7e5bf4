// The unpacked kernel on AVX-512: 32-row panels (two 16-float registers down a column of
// A) times blocks of up to 12 columns, every accumulator in a register. Compiled for
// AVX-512F whatever the build's -march; run only where the CPU has it (nn/direct_gemm.cpp).

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <utility>

#include "nn/direct_gemm_kernels.h"

// Everything after this line is compiled for AVX-512F (headers above keep the build's
// target, so no library code is emitted with instructions the CPU may lack).
#define PNP_TARGET "avx512f"
#include "nn/target_begin.h"

namespace pnp::nn::avx512 {
namespace {

constexpr int kPanelRows = 32;  // two 16-float registers down a column of A
constexpr std::size_t kMaxBlockCols =
    12;  // 24 accumulators + 2 A loads + 1 broadcast of 32 registers

struct RowMasks {
  __mmask16 low, high;
};

RowMasks row_masks(std::ptrdiff_t rows) {
  const auto mask = [](std::ptrdiff_t r) {
    return r >= 16 ? __mmask16{0xFFFF} : static_cast<__mmask16>((1u << r) - 1u);
  };
  return {mask(rows), mask(std::max<std::ptrdiff_t>(0, rows - 16))};
}

// What happens to a block's sums as they are stored.
struct Epilogue {
  RowMasks rows;
  bool accumulate;
  __m512 bias_low, bias_high;  // zero when there is no bias
  bool relu;
  const float* relu_output;  // at this block's first element, leading dimension ldc
};

// C[32 x Cols] (+)= A[32 x k] B[k x Cols]: every accumulator stays in a register.
template <std::size_t Cols>
void block(std::ptrdiff_t k, const float* a, std::ptrdiff_t lda, const float* b,
           std::ptrdiff_t b_row, std::ptrdiff_t b_col, float* c, std::ptrdiff_t ldc,
           const Epilogue& e) {
  __m512 low[Cols], high[Cols];  // NOLINT: registers, not storage
#pragma GCC unroll 16
  for (std::size_t j = 0; j < Cols; ++j) low[j] = high[j] = _mm512_setzero_ps();
  for (std::ptrdiff_t p = 0; p < k; ++p) {
    const __m512 a_low = _mm512_maskz_loadu_ps(e.rows.low, a + p * lda);
    const __m512 a_high = _mm512_maskz_loadu_ps(e.rows.high, a + p * lda + 16);
    const float* bp = b + p * b_row;
#pragma GCC unroll 16
    for (std::size_t j = 0; j < Cols; ++j) {
      const __m512 bj = _mm512_set1_ps(bp[static_cast<std::ptrdiff_t>(j) * b_col]);
      low[j] = _mm512_fmadd_ps(a_low, bj, low[j]);
      high[j] = _mm512_fmadd_ps(a_high, bj, high[j]);
    }
  }
  const __m512 zero = _mm512_setzero_ps();
#pragma GCC unroll 16
  for (std::size_t j = 0; j < Cols; ++j) {
    float* cj = c + static_cast<std::ptrdiff_t>(j) * ldc;
    __m512 add_low = e.bias_low, add_high = e.bias_high;
    if (e.accumulate) {
      add_low = _mm512_maskz_loadu_ps(e.rows.low, cj);
      add_high = _mm512_maskz_loadu_ps(e.rows.high, cj + 16);
    }
    low[j] = _mm512_add_ps(add_low, low[j]);
    high[j] = _mm512_add_ps(add_high, high[j]);
    if (e.relu) {  // max_ps returns its second operand for NaN: NaN stays NaN, as in Eigen
      low[j] = _mm512_max_ps(zero, low[j]);
      high[j] = _mm512_max_ps(zero, high[j]);
    }
    if (e.relu_output) {
      const float* out = e.relu_output + static_cast<std::ptrdiff_t>(j) * ldc;
      const __m512 out_low = _mm512_maskz_loadu_ps(e.rows.low, out);
      const __m512 out_high = _mm512_maskz_loadu_ps(e.rows.high, out + 16);
      low[j] = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(out_low, zero, _CMP_GT_OQ), low[j]);
      high[j] = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(out_high, zero, _CMP_GT_OQ), high[j]);
    }
    _mm512_mask_storeu_ps(cj, e.rows.low, low[j]);
    _mm512_mask_storeu_ps(cj + 16, e.rows.high, high[j]);
  }
}

// All row panels of one block of Cols columns; B's block stays in L1 across them.
template <std::size_t Cols>
void column_block(const DirectGemmOperands& op, std::ptrdiff_t j) {
  const float* b = op.b + j * op.b_col_stride;
  float* c = op.c + j * op.m;
  for (std::ptrdiff_t i = 0; i < op.m; i += kPanelRows) {
    Epilogue e{.rows = row_masks(std::min<std::ptrdiff_t>(kPanelRows, op.m - i)),
               .accumulate = op.accumulate,
               .bias_low = _mm512_setzero_ps(),
               .bias_high = _mm512_setzero_ps(),
               .relu = op.relu,
               .relu_output = op.relu_output ? op.relu_output + j * op.m + i : nullptr};
    if (op.row_bias) {
      e.bias_low = _mm512_maskz_loadu_ps(e.rows.low, op.row_bias + i);
      e.bias_high = _mm512_maskz_loadu_ps(e.rows.high, op.row_bias + i + 16);
    }
    block<Cols>(op.k, op.a + i, op.m, b, op.b_row_stride, op.b_col_stride, c + i, op.m, e);
  }
}

using ColumnBlockFn = void (*)(const DirectGemmOperands&, std::ptrdiff_t);

template <std::size_t... I>
constexpr std::array<ColumnBlockFn, sizeof...(I)> column_blocks(std::index_sequence<I...>) {
  return {&column_block<I + 1>...};
}

// kColumnBlocks[w - 1] handles a block w columns wide.
constexpr auto kColumnBlocks = column_blocks(std::make_index_sequence<kMaxBlockCols>{});

__mmask16 first(std::ptrdiff_t count) {
  return count >= 16 ? __mmask16{0xFFFF} : static_cast<__mmask16>((1u << count) - 1u);
}

// GCC 12's shuffle intrinsics start from _mm512_undefined_ps(), which its own
// -Wuninitialized reports (a known false positive): silenced for this function only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
// One tile: up to 16 source columns of up to 16 rows each, transposed by three rounds of
// shuffles (pairs of floats, then 128-bit lanes) with no trip through memory.
void transpose_tile(const float* src, std::ptrdiff_t lds, std::ptrdiff_t tile_rows,
                    std::ptrdiff_t tile_cols, float* dst, std::ptrdiff_t ldd) {
  __m512 r[16], t[16];  // NOLINT: registers, not storage
  const __mmask16 row_mask = first(tile_rows);
  for (std::ptrdiff_t c = 0; c < 16; ++c)
    r[c] = c < tile_cols ? _mm512_maskz_loadu_ps(row_mask, src + c * lds) : _mm512_setzero_ps();
  for (int i = 0; i < 8; ++i) {
    t[2 * i] = _mm512_unpacklo_ps(r[2 * i], r[2 * i + 1]);
    t[2 * i + 1] = _mm512_unpackhi_ps(r[2 * i], r[2 * i + 1]);
  }
  for (int i = 0; i < 4; ++i) {
    r[4 * i + 0] = _mm512_shuffle_ps(t[4 * i + 0], t[4 * i + 2], _MM_SHUFFLE(1, 0, 1, 0));
    r[4 * i + 1] = _mm512_shuffle_ps(t[4 * i + 0], t[4 * i + 2], _MM_SHUFFLE(3, 2, 3, 2));
    r[4 * i + 2] = _mm512_shuffle_ps(t[4 * i + 1], t[4 * i + 3], _MM_SHUFFLE(1, 0, 1, 0));
    r[4 * i + 3] = _mm512_shuffle_ps(t[4 * i + 1], t[4 * i + 3], _MM_SHUFFLE(3, 2, 3, 2));
  }
  for (int i = 0; i < 2; ++i) {
    for (int q = 0; q < 4; ++q) {
      t[8 * i + q] = _mm512_shuffle_f32x4(r[8 * i + q], r[8 * i + 4 + q], 0x88);
      t[8 * i + 4 + q] = _mm512_shuffle_f32x4(r[8 * i + q], r[8 * i + 4 + q], 0xDD);
    }
  }
  for (int q = 0; q < 8; ++q) {
    r[q] = _mm512_shuffle_f32x4(t[q], t[8 + q], 0x88);
    r[q + 8] = _mm512_shuffle_f32x4(t[q], t[8 + q], 0xDD);
  }
  // r[x] is source row x: destination column x.
  const __mmask16 col_mask = first(tile_cols);
  for (std::ptrdiff_t x = 0; x < tile_rows; ++x)
    _mm512_mask_storeu_ps(dst + x * ldd, col_mask, r[x]);
}
#pragma GCC diagnostic pop

}  // namespace

void transpose(const float* src, std::ptrdiff_t rows, std::ptrdiff_t cols, float* dst) {
  for (std::ptrdiff_t r0 = 0; r0 < rows; r0 += 16) {
    for (std::ptrdiff_t c0 = 0; c0 < cols; c0 += 16) {
      transpose_tile(src + r0 + c0 * rows, rows, std::min<std::ptrdiff_t>(16, rows - r0),
                     std::min<std::ptrdiff_t>(16, cols - c0), dst + c0 + r0 * cols, cols);
    }
  }
}

void gemm(const DirectGemmOperands& op) {
  constexpr auto kMax = static_cast<std::ptrdiff_t>(kMaxBlockCols);
  for (std::ptrdiff_t j = 0; j < op.n; j += kMax) {
    const auto width = static_cast<std::size_t>(std::min(kMax, op.n - j));
    kColumnBlocks[width - 1](op, j);
  }
}

}  // namespace pnp::nn::avx512

#include "nn/target_end.h"
