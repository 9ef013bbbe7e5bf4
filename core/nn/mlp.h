#pragma once
// A multilayer perceptron whose parameters live in one contiguous buffer (and gradients
// in another of the same layout), so that optimisers, Polyak averaging, gradient
// clipping, copying between A3C workers and serialisation all work on flat spans.
//
// forward() and backward() use a caller-owned workspace, so one network can be run on
// several inputs (a critic on replay actions and on policy actions) without clobbering,
// and a steady batch size never allocates.

#include <span>
#include <vector>

#include "common/rng.h"
#include "nn/activation.h"
#include "nn/tensor.h"

namespace pnp::nn {

struct MlpSpec {
  int inputs = 0;
  std::vector<int> hidden;
  int outputs = 0;
  Activation hidden_activation = Activation::kReLU;
  Activation output_activation = Activation::kNone;
  bool operator==(const MlpSpec&) const = default;
};

struct MlpWorkspace {
  Matrix input;
  std::vector<Matrix> post;  // a_l = f(W_l a_{l-1} + b_l)
  std::vector<Matrix> grad;  // scratch for dL/da and dL/dz
  Matrix grad_z;
  std::vector<Matrix> weight_t;  // each layer's W^T, for the input gradient's product
};

class Mlp {
 public:
  explicit Mlp(MlpSpec spec);
  // The floats params() holds for `spec` (tensors aligned as the constructor lays them
  // out), in 64-bit arithmetic and without allocating: what a loader checks a section's
  // size against first. INVALID_ARGUMENT for a width that is not positive.
  static std::size_t flat_size(const MlpSpec& spec);

  const MlpSpec& spec() const { return spec_; }
  int layers() const { return static_cast<int>(layers_.size()); }
  std::span<float> params() { return params_; }
  std::span<const float> params() const { return params_; }
  std::span<float> grads() { return grads_; }
  std::span<const float> grads() const { return grads_; }
  void zero_grads();

  // Uniform(-1/sqrt(fan_in), 1/sqrt(fan_in)) weights and biases (PyTorch's default).
  void initialise(Rng& rng);

  // x: inputs x batch. Returns outputs x batch (a reference into the workspace).
  const Matrix& forward(const MatrixRef& x, MlpWorkspace& ws) const;

  // After forward() with the same workspace: adds dL/dparams to grads() when
  // accumulate_param_grads, and writes dL/dx to *dx when dx is not null.
  void backward(MlpWorkspace& ws, const MatrixRef& dy, bool accumulate_param_grads, Matrix* dx);
  // The same, adding dL/dparams into `grads_out` (same layout as grads(); empty: none),
  // so that several threads can back-propagate through one network at once.
  // weight_columns >= 0: parameter gradients come from the first weight_columns samples
  // only, while dx covers every sample (one pass serves a loss on the parameters and
  // another on the inputs, as the DDPG update needs for Q(s, a) and Q(s, pi(s))).
  void backward_into(MlpWorkspace& ws, const MatrixRef& dy, std::span<float> grads_out, Matrix* dx,
                     Eigen::Index weight_columns = -1) const;

  ConstMatrixMap weight(int layer) const;
  ConstVectorMap bias(int layer) const;

 private:
  struct Layer {
    int in = 0, out = 0;
    std::size_t weight_offset = 0, bias_offset = 0;
    Activation activation = Activation::kNone;
  };
  MatrixMap weight_grad(int layer);
  VectorMap bias_grad(int layer);

  MlpSpec spec_;
  std::vector<Layer> layers_;
  AlignedFloats params_;
  AlignedFloats grads_;
};

}  // namespace pnp::nn
