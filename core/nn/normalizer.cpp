#include "nn/normalizer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"

namespace pnp::nn {

Normalizer::Normalizer(int size, double clip, double std_floor)
    : clip_(clip), std_floor_(std_floor) {
  if (size <= 0)
    throw_invalid_argument("normalizer size", "a positive integer", std::to_string(size));
  const auto n = static_cast<std::size_t>(size);
  sum_.assign(n, 0.0);
  sumsq_.assign(n, 0.0);
  mean_.assign(n, 0.0f);
  std_.assign(n, 1.0f);
}

void Normalizer::update(std::span<const double> sample) {
  if (sample.size() != sum_.size()) throw_internal("Normalizer::update: size mismatch");
  for (std::size_t i = 0; i < sample.size(); ++i) {
    sum_[i] += sample[i];
    sumsq_[i] += sample[i] * sample[i];
  }
  count_ += 1;
}

void Normalizer::refresh() {
  if (count_ <= 0) return;
  for (std::size_t i = 0; i < sum_.size(); ++i) {
    const double mean = sum_[i] / count_;
    const double var = std::max(std_floor_ * std_floor_, sumsq_[i] / count_ - mean * mean);
    mean_[i] = static_cast<float>(mean);
    std_[i] = static_cast<float>(std::sqrt(var));
  }
}

void Normalizer::normalize_into(std::span<const double> in, Matrix& out, Eigen::Index row,
                                Eigen::Index col) const {
  const auto c = static_cast<float>(clip_);
  for (std::size_t i = 0; i < mean_.size(); ++i) {
    const float z = (static_cast<float>(in[i]) - mean_[i]) / std_[i];
    out(row + static_cast<Eigen::Index>(i), col) = std::clamp(z, -c, c);
  }
}

void Normalizer::restore(std::span<const double> sums, std::span<const double> sums_of_squares,
                         double count) {
  if (sums.size() != sum_.size() || sums_of_squares.size() != sumsq_.size()) {
    throw_internal("Normalizer::restore: size mismatch");
  }
  std::copy(sums.begin(), sums.end(), sum_.begin());
  std::copy(sums_of_squares.begin(), sums_of_squares.end(), sumsq_.begin());
  count_ = count;
  refresh();
}

}  // namespace pnp::nn
