#pragma once
// An LSTM cell (gate order input, forget, cell, output, as in PyTorch) with one flat
// parameter buffer [W (4H x I) | U (4H x H) | b (4H)], stepped forward one time step at a
// time and back-propagated through time from per-step caches.

#include <span>
#include <vector>

#include "common/rng.h"
#include "nn/tensor.h"

namespace pnp::nn {

struct LstmStepCache {
  Matrix x, h_prev, c_prev;
  Matrix gates;  // 4H x batch, after the non-linearities
  Matrix c, tanh_c;
};

class LstmCell {
 public:
  LstmCell(int inputs, int hidden);

  int inputs() const { return inputs_; }
  int hidden() const { return hidden_; }
  std::span<float> params() { return params_; }
  std::span<const float> params() const { return params_; }
  std::span<float> grads() { return grads_; }
  std::span<const float> grads() const { return grads_; }
  void zero_grads();
  void initialise(Rng& rng);  // Uniform(-1/sqrt(H), 1/sqrt(H)), as PyTorch

  // One step: (x, h_prev, c_prev) -> (h, c); the cache keeps what backward needs.
  void forward(const MatrixRef& x, const MatrixRef& h_prev, const MatrixRef& c_prev,
               LstmStepCache& cache, Matrix& h) const;

  // Given dL/dh and dL/dc at this step's outputs, adds parameter gradients and returns
  // dL/dx (if dx), dL/dh_prev and dL/dc_prev.
  void backward(const LstmStepCache& cache, const MatrixRef& dh, const MatrixRef& dc, Matrix* dx,
                Matrix& dh_prev, Matrix& dc_prev);

 private:
  ConstMatrixMap w() const { return {params_.data(), 4 * hidden_, inputs_}; }
  ConstMatrixMap u() const { return {params_.data() + u_offset_, 4 * hidden_, hidden_}; }
  ConstVectorMap b() const { return {params_.data() + b_offset_, 4 * hidden_}; }

  int inputs_, hidden_;
  std::size_t u_offset_, b_offset_;
  AlignedFloats params_, grads_;
  Matrix dgates_;  // scratch
};

}  // namespace pnp::nn
