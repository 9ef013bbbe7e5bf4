#pragma once
// The High Level Choreographer's network: [normalised observation (25); normalised
// episode goal (3); optionally the three subtask predicates as 0/1 (approach reached,
// object grasped, object placed)] -> FC 128 -> FC 128 (ELU) -> LSTM cell (32) -> policy head (3
// logits: approach, manipulate, retract) and value head. The predicates are functions of
// the observation and goal; giving them explicitly lets the choreographer see which phase
// it is in from the start (without them greedy evaluation locked onto repeating one
// subtask: 4% success after 20k steps). The whole network is trained (the original froze
// a trunk copied from behaviour cloning). One step per decision; back-propagation
// through the episode's decisions.

#include <span>
#include <string_view>
#include <vector>

#include "common/rng.h"
#include "nn/lstm_cell.h"
#include "nn/mlp.h"
#include "nn/normalizer.h"
#include "sim/observation.h"
#include "sim/subtask.h"

namespace pnp::rl {

struct ChoreographerSpec {
  std::vector<int> trunk{128, 128};
  int lstm = 32;
  // Domain knowledge, computed from observation and goal: the three predicates as inputs,
  // and finished subtasks masked out of the choices (rl/hlc_episode.h). The paper's
  // choreographer has neither: it sees observation and goal only.
  bool predicate_inputs = true;
  bool mask_finished = true;
  // An action prior: this is added to the logit of the subtask that follows, in the order
  // the experts were trained (approach, manipulate, retract), the furthest one whose
  // predicate holds: a fixed bias that the learned logits can outweigh. 0: none (the
  // paper's).
  double chain_prior = 0.0;
  int input_size() const;
  // INVALID_ARGUMENT naming `prefix` + lstm, trunk or chain_prior outside the bounds of
  // rl/network_limits.h: what a training request ("network.") and a checkpoint's metadata
  // ("checkpoint ") may ask for.
  void validate(std::string_view prefix) const;
  bool operator==(const ChoreographerSpec&) const = default;
};

struct DecisionCache {
  nn::MlpWorkspace trunk, policy, value;
  nn::LstmStepCache lstm;
  nn::Matrix h;  // LSTM output after this decision
};

class ChoreographerNet {
 public:
  explicit ChoreographerNet(const ChoreographerSpec& spec);
  const ChoreographerSpec& spec() const { return spec_; }

  void initialise(Rng& rng);
  void reset_state();  // zero LSTM state: start of an episode

  // One decision from a normalised input column: fills logits (3) and value.
  void step(const nn::Matrix& input, DecisionCache& cache,
            std::array<double, sim::kNumSubtasks>& logits, double& value);

  // Back-propagates through the episode: dlogits[t] (3) and dvalue[t] per decision.
  void backward(std::vector<DecisionCache>& caches, std::span<const std::array<double, 3>> dlogits,
                std::span<const double> dvalue);

  // All parameters and gradients as one list of flat blocks, in a fixed order.
  std::vector<std::span<float>> parameter_blocks();
  std::vector<std::span<float>> gradient_blocks();
  std::size_t parameter_count() const;
  void zero_grads();

  nn::Normalizer& normalizer() { return normalizer_; }
  const nn::Normalizer& normalizer() const { return normalizer_; }
  void encode(const sim::Observation& observation, const sim::Goal& goal,
              const sim::TaskState& state, nn::Matrix& out) const;

 private:
  ChoreographerSpec spec_;
  nn::Mlp trunk_;
  nn::LstmCell lstm_;
  nn::Mlp policy_head_, value_head_;
  nn::Normalizer normalizer_;
  nn::Matrix h_, c_;  // recurrent state
};

}  // namespace pnp::rl
