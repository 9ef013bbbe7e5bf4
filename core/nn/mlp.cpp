#include "nn/mlp.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"
#include "nn/blas_threads.h"
#include "nn/gemm.h"

namespace pnp::nn {
namespace {

// Tensors start on 16-float (64-byte) boundaries inside the flat buffer.
std::size_t aligned(std::size_t n) {
  return (n + 15) & ~std::size_t{15};
}

void validate(const MlpSpec& spec) {
  if (spec.inputs <= 0)
    throw_invalid_argument("inputs", "a positive width", std::to_string(spec.inputs));
  if (spec.outputs <= 0)
    throw_invalid_argument("outputs", "a positive width", std::to_string(spec.outputs));
  for (std::size_t i = 0; i < spec.hidden.size(); ++i) {
    if (spec.hidden[i] <= 0) {
      throw_invalid_argument("hidden[" + std::to_string(i) + "]", "a positive width",
                             std::to_string(spec.hidden[i]));
    }
  }
}

std::vector<int> layer_widths(const MlpSpec& spec) {
  std::vector<int> widths{spec.inputs};
  widths.insert(widths.end(), spec.hidden.begin(), spec.hidden.end());
  widths.push_back(spec.outputs);
  return widths;
}

std::size_t weight_count(int in, int out) {
  return static_cast<std::size_t>(in) * static_cast<std::size_t>(out);
}

}  // namespace

std::size_t Mlp::flat_size(const MlpSpec& spec) {
  validate(spec);
  const std::vector<int> widths = layer_widths(spec);
  std::size_t size = 0;
  for (std::size_t l = 0; l + 1 < widths.size(); ++l)
    size += aligned(weight_count(widths[l], widths[l + 1])) +
            aligned(static_cast<std::size_t>(widths[l + 1]));
  return size;
}

Mlp::Mlp(MlpSpec spec) : spec_(std::move(spec)) {
  pin_blas_to_one_thread();
  const std::size_t size = flat_size(spec_);
  const std::vector<int> widths = layer_widths(spec_);
  std::size_t offset = 0;
  for (std::size_t l = 0; l + 1 < widths.size(); ++l) {
    Layer layer;
    layer.in = widths[l];
    layer.out = widths[l + 1];
    layer.weight_offset = offset;
    offset += aligned(weight_count(layer.in, layer.out));
    layer.bias_offset = offset;
    offset += aligned(static_cast<std::size_t>(layer.out));
    layer.activation = l + 2 == widths.size() ? spec_.output_activation : spec_.hidden_activation;
    layers_.push_back(layer);
  }
  params_.assign(size, 0.0f);
  grads_.assign(size, 0.0f);
}

void Mlp::zero_grads() {
  std::fill(grads_.begin(), grads_.end(), 0.0f);
}

void Mlp::initialise(Rng& rng) {
  std::fill(params_.begin(), params_.end(), 0.0f);
  for (const Layer& layer : layers_) {
    const double bound = 1.0 / std::sqrt(static_cast<double>(layer.in));
    for (std::size_t i = 0; i < weight_count(layer.in, layer.out); ++i) {
      params_[layer.weight_offset + i] = static_cast<float>(rng.uniform(-bound, bound));
    }
    for (int i = 0; i < layer.out; ++i) {
      params_[layer.bias_offset + static_cast<std::size_t>(i)] =
          static_cast<float>(rng.uniform(-bound, bound));
    }
  }
}

ConstMatrixMap Mlp::weight(int l) const {
  const Layer& layer = layers_[static_cast<std::size_t>(l)];
  return {params_.data() + layer.weight_offset, layer.out, layer.in};
}
ConstVectorMap Mlp::bias(int l) const {
  const Layer& layer = layers_[static_cast<std::size_t>(l)];
  return {params_.data() + layer.bias_offset, layer.out};
}
MatrixMap Mlp::weight_grad(int l) {
  const Layer& layer = layers_[static_cast<std::size_t>(l)];
  return {grads_.data() + layer.weight_offset, layer.out, layer.in};
}
VectorMap Mlp::bias_grad(int l) {
  const Layer& layer = layers_[static_cast<std::size_t>(l)];
  return {grads_.data() + layer.bias_offset, layer.out};
}

const Matrix& Mlp::forward(const MatrixRef& x, MlpWorkspace& ws) const {
  if (x.rows() != spec_.inputs) {
    throw_invalid_argument("mlp input", std::to_string(spec_.inputs) + " rows",
                           std::to_string(x.rows()));
  }
  const auto n = layers_.size();
  ws.post.resize(n);
  ensure_shape(ws.input, x.rows(), x.cols());
  ws.input = x;
  const Matrix* a = &ws.input;
  for (std::size_t l = 0; l < n; ++l) {
    Matrix& z = ws.post[l];
    const Layer& layer = layers_[l];
    const bool relu = layer.activation == Activation::kReLU;  // fused into the product
    gemm_bias(params_.data() + layer.weight_offset, layer.out, layer.in, *a,
              params_.data() + layer.bias_offset, relu, z);
    if (!relu) apply_activation(layer.activation, z);
    a = &z;
  }
  return ws.post.back();
}

void Mlp::backward(MlpWorkspace& ws, const MatrixRef& dy, bool accumulate_param_grads, Matrix* dx) {
  backward_into(ws, dy, accumulate_param_grads ? std::span<float>(grads_) : std::span<float>(), dx);
}

void Mlp::backward_into(MlpWorkspace& ws, const MatrixRef& dy, std::span<float> grads_out,
                        Matrix* dx, Eigen::Index weight_columns) const {
  const auto n = layers_.size();
  const Eigen::Index wc = weight_columns < 0 ? dy.cols() : weight_columns;
  if (wc > dy.cols()) throw_internal("Mlp::backward_into: more weight columns than samples");
  // grad[2] holds dy; the layers' input gradients alternate between grad[0] and grad[1],
  // so each buffer takes the same shape at every pass (dy in a buffer a layer also wrote
  // would be resized back and forth: two allocations per pass).
  ws.grad.resize(3);
  ws.weight_t.resize(n);  // one per layer: a shared one would reallocate at every layer
  Matrix* upstream = &ws.grad[2];
  ensure_shape(*upstream, dy.rows(), dy.cols());
  *upstream = dy;
  // Whether upstream is already dL/dz: the product of the layer above fused this layer's
  // ReLU derivative into its store, saving a pass over the batch.
  bool upstream_is_grad_z = false;
  for (std::size_t l = n; l-- > 0;) {
    const Matrix* grad_z = upstream;
    if (!upstream_is_grad_z) {
      activation_backward(layers_[l].activation, ws.post[l], *upstream, ws.grad_z);
      grad_z = &ws.grad_z;
    }
    const Matrix& input = l == 0 ? ws.input : ws.post[l - 1];
    const Layer& layer = layers_[l];
    const float* w = params_.data() + layer.weight_offset;
    if (!grads_out.empty()) {
      // Column-major: the first wc samples are the leading wc columns of both.
      gemm_accumulate(false, true, grad_z->data(), grad_z->rows(), wc, input.data(), input.rows(),
                      wc, grads_out.data() + layer.weight_offset);
      VectorMap(grads_out.data() + layer.bias_offset, layer.out) +=
          grad_z->leftCols(wc).rowwise().sum();
    }
    // Never the buffer grad_z is in.
    Matrix* target = l == 0 ? dx : (upstream == &ws.grad[0] ? &ws.grad[1] : &ws.grad[0]);
    const bool fuse_relu = l != 0 && layers_[l - 1].activation == Activation::kReLU;
    if (target) {
      gemm_input_gradient(w, layer.out, layer.in, *grad_z, fuse_relu ? &ws.post[l - 1] : nullptr,
                          ws.weight_t[l], *target);
    }
    if (l != 0) {
      upstream = target;
      upstream_is_grad_z = fuse_relu;
    }
  }
}

}  // namespace pnp::nn
