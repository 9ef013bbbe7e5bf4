#pragma once
// Running mean / standard deviation per feature, as in the original HER code: inputs are
// normalised to (x - mean) / max(std, std_floor) and clipped to +-clip. Statistics are
// accumulated in double and published to float copies by refresh(), so normalising in
// the hot path reads two small float vectors.

#include <cstdint>
#include <span>
#include <vector>

#include "nn/tensor.h"

namespace pnp::nn {

class Normalizer {
 public:
  explicit Normalizer(int size, double clip = 5.0, double std_floor = 0.01);

  int size() const { return static_cast<int>(sum_.size()); }
  void update(std::span<const double> sample);  // one sample of size()
  void refresh();                               // publish mean/std for normalize()

  // Writes the normalised values of `in` into column `col` of `out`, from row `row`.
  void normalize_into(std::span<const double> in, Matrix& out, Eigen::Index row,
                      Eigen::Index col) const;

  std::span<const float> mean() const { return mean_; }
  std::span<const float> stddev() const { return std_; }
  double count() const { return count_; }
  double clip() const { return clip_; }
  double std_floor() const { return std_floor_; }

  // For checkpoints.
  std::span<const double> sums() const { return sum_; }
  std::span<const double> sums_of_squares() const { return sumsq_; }
  void restore(std::span<const double> sums, std::span<const double> sums_of_squares, double count);

 private:
  double clip_, std_floor_;
  std::vector<double> sum_, sumsq_;
  double count_ = 0;
  std::vector<float> mean_, std_;
};

}  // namespace pnp::nn
