#pragma once
// Element-wise activations and their derivatives expressed through the layer's output
// (and pre-activation where needed), so backward needs no extra buffers.

#include <string_view>

#include "nn/tensor.h"

namespace pnp::nn {

enum class Activation { kNone, kReLU, kTanh, kELU };

std::string_view activation_name(Activation a);
Activation parse_activation(std::string_view name, std::string_view field = "activation");

// out = f(z), in place allowed.
void apply_activation(Activation a, const Matrix& z, Matrix& out);
// dz = dout * f'(z), given z and out = f(z).
void activation_backward(Activation a, const Matrix& z, const Matrix& out, const Matrix& dout,
                         Matrix& dz);

}  // namespace pnp::nn
