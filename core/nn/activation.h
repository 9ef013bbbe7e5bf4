#pragma once
// Element-wise activations and their derivatives expressed through the layer's output
// alone (f'(z) from f(z): every activation here is monotonic with f(z) > 0 exactly when
// z > 0), so forward applies them in place and keeps no pre-activations.

#include <string_view>

#include "nn/tensor.h"

namespace pnp::nn {

enum class Activation { kNone, kReLU, kTanh, kELU };

std::string_view activation_name(Activation a);
Activation parse_activation(std::string_view name, std::string_view field = "activation");

// z := f(z).
void apply_activation(Activation a, Matrix& z);
// dz = dout * f'(z), given out = f(z).
void activation_backward(Activation a, const Matrix& out, const Matrix& dout, Matrix& dz);

}  // namespace pnp::nn
