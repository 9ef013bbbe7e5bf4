#include "rl/choreographer_net.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "rl/network_limits.h"

namespace pnp::rl {
namespace {

constexpr int kNormalised = sim::kObservationSize + sim::kGoalSize;

}  // namespace

int ChoreographerSpec::input_size() const {
  return kNormalised + (predicate_inputs ? sim::kNumSubtasks : 0);
}

void ChoreographerSpec::validate(std::string_view prefix) const {
  const std::string name(prefix);
  check_chain_prior(name + "chain_prior", chain_prior);
  if (lstm <= 0 || lstm > kMaxLstmWidth) {
    throw_invalid_argument(name + "lstm", "a width from 1 to " + std::to_string(kMaxLstmWidth),
                           std::to_string(lstm));
  }
  // The trunk feeds the LSTM's four gates.
  check_layer_widths(name + "trunk", trunk, input_size(), 4 * lstm);
}

ChoreographerNet::ChoreographerNet(const ChoreographerSpec& spec)
    : spec_(spec),
      trunk_({spec.input_size(), std::vector<int>(spec.trunk.begin(), spec.trunk.end() - 1),
              spec.trunk.back(), nn::Activation::kELU, nn::Activation::kELU}),
      lstm_(spec.trunk.back(), spec.lstm),
      policy_head_({spec.lstm, {}, sim::kNumSubtasks}),
      value_head_({spec.lstm, {}, 1}),
      normalizer_(kNormalised, 5.0, 0.01) {
  reset_state();
}

void ChoreographerNet::initialise(Rng& rng) {
  trunk_.initialise(rng);
  lstm_.initialise(rng);
  policy_head_.initialise(rng);
  value_head_.initialise(rng);
  // Small policy logits at the start: near-uniform choices, the most exploratory start.
  for (float& p : policy_head_.params()) p *= 0.01f;
}

void ChoreographerNet::reset_state() {
  h_ = nn::Matrix::Zero(spec_.lstm, 1);
  c_ = nn::Matrix::Zero(spec_.lstm, 1);
}

void ChoreographerNet::encode(const sim::Observation& observation, const sim::Goal& goal,
                              const sim::TaskState& state, nn::Matrix& out) const {
  double raw[kNormalised];
  for (int k = 0; k < sim::kObservationSize; ++k) raw[k] = observation(k);
  for (int k = 0; k < sim::kGoalSize; ++k) raw[sim::kObservationSize + k] = goal(k);
  nn::ensure_shape(out, spec_.input_size(), 1);
  normalizer_.normalize_into(raw, out, 0, 0);
  if (!spec_.predicate_inputs) return;
  for (sim::Subtask s : sim::kAllSubtasks) {
    out(kNormalised + static_cast<int>(s), 0) =
        sim::objective_done(sim::objective_of(s), state) ? 1.0f : 0.0f;
  }
}

void ChoreographerNet::step(const nn::Matrix& input, DecisionCache& cache,
                            std::array<double, sim::kNumSubtasks>& logits, double& value) {
  const nn::Matrix& features = trunk_.forward(input, cache.trunk);
  nn::Matrix h;
  lstm_.forward(features, h_, c_, cache.lstm, h);
  c_ = cache.lstm.c;
  h_ = h;
  cache.h = h;
  const nn::Matrix& l = policy_head_.forward(h, cache.policy);
  for (int k = 0; k < sim::kNumSubtasks; ++k)
    logits[static_cast<std::size_t>(k)] = static_cast<double>(l(k, 0));
  value = static_cast<double>(value_head_.forward(h, cache.value)(0, 0));
}

void ChoreographerNet::backward(std::vector<DecisionCache>& caches,
                                std::span<const std::array<double, 3>> dlogits,
                                std::span<const double> dvalue) {
  nn::Matrix dh_next = nn::Matrix::Zero(spec_.lstm, 1), dc_next = dh_next, dh_prev, dc_prev,
             dh_policy, dh_value, dfeatures;
  nn::Matrix dl(sim::kNumSubtasks, 1), dv(1, 1);
  for (std::size_t t = caches.size(); t-- > 0;) {
    for (int k = 0; k < sim::kNumSubtasks; ++k)
      dl(k, 0) = static_cast<float>(dlogits[t][static_cast<std::size_t>(k)]);
    dv(0, 0) = static_cast<float>(dvalue[t]);
    policy_head_.backward(caches[t].policy, dl, true, &dh_policy);
    value_head_.backward(caches[t].value, dv, true, &dh_value);
    const nn::Matrix dh = dh_next + dh_policy + dh_value;
    lstm_.backward(caches[t].lstm, dh, dc_next, &dfeatures, dh_prev, dc_prev);
    trunk_.backward(caches[t].trunk, dfeatures, true, nullptr);
    dh_next = dh_prev;
    dc_next = dc_prev;
  }
}

std::vector<std::span<float>> ChoreographerNet::parameter_blocks() {
  return {trunk_.params(), lstm_.params(), policy_head_.params(), value_head_.params()};
}
std::vector<std::span<float>> ChoreographerNet::gradient_blocks() {
  return {trunk_.grads(), lstm_.grads(), policy_head_.grads(), value_head_.grads()};
}
std::size_t ChoreographerNet::parameter_count() const {
  return trunk_.params().size() + lstm_.params().size() + policy_head_.params().size() +
         value_head_.params().size();
}
void ChoreographerNet::zero_grads() {
  trunk_.zero_grads();
  lstm_.zero_grads();
  policy_head_.zero_grads();
  value_head_.zero_grads();
}

}  // namespace pnp::rl
