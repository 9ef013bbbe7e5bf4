#include "nn/activation.h"

#include <array>

#include "common/enum_names.h"

namespace pnp::nn {

std::string_view activation_name(Activation a) {
  switch (a) {
    case Activation::kNone:
      return "none";
    case Activation::kReLU:
      return "relu";
    case Activation::kTanh:
      return "tanh";
    case Activation::kELU:
      return "elu";
  }
  return "unknown";
}

Activation parse_activation(std::string_view name, std::string_view field) {
  static constexpr std::array<Activation, 4> kAll{Activation::kNone, Activation::kReLU,
                                                  Activation::kTanh, Activation::kELU};
  return parse_enum<Activation>(name, kAll, &activation_name, field);
}

void apply_activation(Activation a, Matrix& z) {
  switch (a) {
    case Activation::kNone:
      break;
    case Activation::kReLU:
      z = z.cwiseMax(0.0f);
      break;
    case Activation::kTanh:
      z = z.array().tanh();
      break;
    case Activation::kELU:
      z = (z.array() > 0.0f).select(z.array(), z.array().exp() - 1.0f);
      break;
  }
}

void activation_backward(Activation a, const Matrix& out, const Matrix& dout, Matrix& dz) {
  ensure_shape(dz, dout.rows(), dout.cols());
  switch (a) {
    case Activation::kNone:
      dz = dout;
      break;
    case Activation::kReLU:
      dz = (out.array() > 0.0f).select(dout.array(), 0.0f);
      break;
    case Activation::kTanh:
      dz = dout.array() * (1.0f - out.array().square());
      break;
    case Activation::kELU:
      dz = (out.array() > 0.0f).select(dout.array(), dout.array() * (out.array() + 1.0f));
      break;
  }
}

}  // namespace pnp::nn
