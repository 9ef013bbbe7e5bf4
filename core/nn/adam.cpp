#include "nn/adam.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp::nn {

void validate(const AdamConfig& c, const char* prefix) {
  const std::string p(prefix);
  if (!(c.learning_rate > 0) || !std::isfinite(c.learning_rate)) {
    throw_invalid_argument(p + ".learning_rate", "a positive finite number",
                           std::to_string(c.learning_rate));
  }
  if (!(c.beta1 >= 0 && c.beta1 < 1))
    throw_invalid_argument(p + ".beta1", "a value in [0, 1)", std::to_string(c.beta1));
  if (!(c.beta2 >= 0 && c.beta2 < 1))
    throw_invalid_argument(p + ".beta2", "a value in [0, 1)", std::to_string(c.beta2));
  if (!(c.epsilon > 0))
    throw_invalid_argument(p + ".epsilon", "a positive number", std::to_string(c.epsilon));
}

Adam::Adam(std::size_t parameter_count, AdamConfig config)
    : config_(config), m_(parameter_count, 0.0f), v_(parameter_count, 0.0f) {
  validate(config_);
}

void Adam::step(std::span<float> params, std::span<const float> grads) {
  begin_step();
  apply(params, grads, 0, m_.size());
}

void Adam::begin_step() {
  ++t_;
  const double c1 = 1.0 - std::pow(config_.beta1, static_cast<double>(t_));
  const double c2 = 1.0 - std::pow(config_.beta2, static_cast<double>(t_));
  step_size_ = static_cast<float>(config_.learning_rate * std::sqrt(c2) / c1);
  epsilon_ = static_cast<float>(config_.epsilon * std::sqrt(c2));
}

void Adam::apply(std::span<float> params, std::span<const float> grads, std::size_t begin,
                 std::size_t count) {
  const std::array<std::span<const float>, 1> one{grads};
  apply(params, one, begin, count);
}

void Adam::apply(std::span<float> params, std::span<const std::span<const float>> partials,
                 std::size_t begin, std::size_t count) {
  if (params.size() != m_.size() || begin + count > m_.size() || partials.empty()) {
    throw_internal("Adam::apply: parameter count differs from the optimiser's");
  }
  for (const auto& g : partials) {
    if (g.size() != m_.size()) throw_internal("Adam::apply: gradient size differs");
  }
  const auto b1 = static_cast<float>(config_.beta1), b2 = static_cast<float>(config_.beta2);
  // Chunks small enough that the gradient, moments and parameters stay in L1 across the
  // three passes; a multiple of kSliceAlignment, so the vectorised loops and the scalar
  // tail cover the same elements as one pass over the slice would.
  constexpr std::size_t kChunk = 32 * kSliceAlignment;
  alignas(64) std::array<float, kChunk> sum;
  for (std::size_t at = begin; at < begin + count; at += kChunk) {
    const auto n = static_cast<Eigen::Index>(std::min(kChunk, begin + count - at));
    const float* g_data = partials[0].data() + at;
    if (partials.size() > 1) {
      Eigen::Map<Eigen::ArrayXf> acc(sum.data(), n);
      acc = Eigen::Map<const Eigen::ArrayXf>(g_data, n);
      for (std::size_t k = 1; k < partials.size(); ++k)
        acc += Eigen::Map<const Eigen::ArrayXf>(partials[k].data() + at, n);
      g_data = sum.data();
    }
    Eigen::Map<Eigen::ArrayXf> p(params.data() + at, n), m(m_.data() + at, n), v(v_.data() + at, n);
    Eigen::Map<const Eigen::ArrayXf> g(g_data, n);
    m = b1 * m + (1.0f - b1) * g;
    v = b2 * v + (1.0f - b2) * g.square();
    p -= step_size_ * m / (v.sqrt() + epsilon_);
  }
}

void Adam::restore(std::span<const float> m, std::span<const float> v, std::int64_t t) {
  if (m.size() != m_.size() || v.size() != v_.size())
    throw_internal("Adam::restore: size mismatch");
  std::copy(m.begin(), m.end(), m_.begin());
  std::copy(v.begin(), v.end(), v_.begin());
  t_ = t;
}

}  // namespace pnp::nn
