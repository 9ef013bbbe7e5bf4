#include "nn/adam.h"

#include <Eigen/Core>
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
  if (params.size() != m_.size() || grads.size() != m_.size() || begin + count > m_.size()) {
    throw_internal("Adam::apply: parameter count differs from the optimiser's");
  }
  const auto n = static_cast<Eigen::Index>(count);
  Eigen::Map<Eigen::ArrayXf> p(params.data() + begin, n), m(m_.data() + begin, n),
      v(v_.data() + begin, n);
  Eigen::Map<const Eigen::ArrayXf> g(grads.data() + begin, n);
  const auto b1 = static_cast<float>(config_.beta1), b2 = static_cast<float>(config_.beta2);
  m = b1 * m + (1.0f - b1) * g;
  v = b2 * v + (1.0f - b2) * g.square();
  p -= step_size_ * m / (v.sqrt() + epsilon_);
}

void Adam::restore(std::span<const float> m, std::span<const float> v, std::int64_t t) {
  if (m.size() != m_.size() || v.size() != v_.size())
    throw_internal("Adam::restore: size mismatch");
  std::copy(m.begin(), m.end(), m_.begin());
  std::copy(v.begin(), v.end(), v_.begin());
  t_ = t;
}

}  // namespace pnp::nn
