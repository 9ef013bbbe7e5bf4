#pragma once
// Adam over a flat parameter buffer (Kingma and Ba, with bias correction). The moment
// buffers are sized once; step() allocates nothing. One Adam can be shared by several
// A3C workers: they apply gradients to the same parameters and statistics in turn.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace pnp::nn {

// Elements per 64 bytes: where a slice of a flat parameter buffer may begin (see apply()).
inline constexpr std::size_t kSliceAlignment = 16;

struct AdamConfig {
  double learning_rate = 1e-3;
  double beta1 = 0.9;
  double beta2 = 0.999;
  double epsilon = 1e-8;
};

void validate(const AdamConfig& config, const char* field_prefix = "adam");

class Adam {
 public:
  Adam(std::size_t parameter_count, AdamConfig config);

  void step(std::span<float> params, std::span<const float> grads);
  // step() in parts, for several threads: begin_step() once, then apply() on disjoint
  // slices [begin, begin + count) of the parameters. Slices that begin at multiples of
  // kSliceAlignment give exactly step()'s result (the vectorised and the scalar tail
  // code round differently, so the split must not move elements between them).
  void begin_step();
  void apply(std::span<float> params, std::span<const float> grads, std::size_t begin,
             std::size_t count);
  // The same with the gradient given as the sum, in order, of `partials` (each the full
  // parameter count): several threads' gradients of one batch, summed on the fly in a fixed
  // order, so the result does not depend on timing and the sum is never written out.
  void apply(std::span<float> params, std::span<const std::span<const float>> partials,
             std::size_t begin, std::size_t count);
  void set_learning_rate(double lr) { config_.learning_rate = lr; }
  const AdamConfig& config() const { return config_; }
  std::int64_t steps() const { return t_; }

  // For checkpoints: moments and step count.
  std::span<const float> first_moment() const { return m_; }
  std::span<const float> second_moment() const { return v_; }
  void restore(std::span<const float> m, std::span<const float> v, std::int64_t t);

 private:
  AdamConfig config_;
  std::vector<float, Eigen::aligned_allocator<float>> m_, v_;
  std::int64_t t_ = 0;
  float step_size_ = 0, epsilon_ = 0;  // this step's, bias-corrected (begin_step)
};

}  // namespace pnp::nn
