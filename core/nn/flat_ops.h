#pragma once
// Operations on flat parameter and gradient buffers.

#include <span>

namespace pnp::nn {

// target <- polyak * target + (1 - polyak) * source.
void polyak_update(std::span<float> target, std::span<const float> source, double polyak);

// Scales grads so their global L2 norm is at most max_norm; returns the norm before.
double clip_grad_norm(std::span<float> grads, double max_norm);

double l2_norm(std::span<const float> values);

void copy_into(std::span<float> dst, std::span<const float> src);

}  // namespace pnp::nn
