#include "nn/flat_ops.h"

#include <Eigen/Core>
#include <cmath>

#include "common/error.h"

namespace pnp::nn {
namespace {

Eigen::Map<Eigen::ArrayXf> as_array(std::span<float> s) {
  return {s.data(), static_cast<Eigen::Index>(s.size())};
}
Eigen::Map<const Eigen::ArrayXf> as_array(std::span<const float> s) {
  return {s.data(), static_cast<Eigen::Index>(s.size())};
}

}  // namespace

void polyak_update(std::span<float> target, std::span<const float> source, double polyak) {
  if (target.size() != source.size()) throw_internal("polyak_update: size mismatch");
  const auto p = static_cast<float>(polyak);
  as_array(target) = p * as_array(target) + (1.0f - p) * as_array(source);
}

double l2_norm(std::span<const float> values) {
  return std::sqrt(as_array(values).cast<double>().square().sum());
}

double clip_grad_norm(std::span<float> grads, double max_norm) {
  const double norm = l2_norm(grads);
  if (norm > max_norm && norm > 0) as_array(grads) *= static_cast<float>(max_norm / norm);
  return norm;
}

void copy_into(std::span<float> dst, std::span<const float> src) {
  if (dst.size() != src.size()) throw_internal("copy_into: size mismatch");
  std::copy(src.begin(), src.end(), dst.begin());
}

}  // namespace pnp::nn
