#pragma once
// The unpacked kernels, one namespace per instruction set, each compiled for its own
// target in its own file whatever the build's -march (so one binary carries both). Called
// only through nn/direct_gemm.h, which checks the operands and that the CPU has the set.

#include <cstddef>

#include "nn/direct_gemm.h"

namespace pnp::nn::avx512 {
void gemm(const DirectGemmOperands& op);
void transpose(const float* src, std::ptrdiff_t rows, std::ptrdiff_t cols, float* dst);
}  // namespace pnp::nn::avx512

namespace pnp::nn::avx2 {
void gemm(const DirectGemmOperands& op);
void transpose(const float* src, std::ptrdiff_t rows, std::ptrdiff_t cols, float* dst);
}  // namespace pnp::nn::avx2
