#pragma once
// One episode driven by the choreographer: at each decision it picks a subtask, whose
// expert runs until its termination predicate fires (after at least one step), its step
// cap, or the episode's end; then it decides again, until the episode's last step (50; 75
// on the arm) or until retract ends by its predicate (the object is placed: the arm then
// idles, gripper closed, to the last step). Any subtask whose predicate does not already
// hold may be picked at any decision. Sparse reward: +1 at the last decision if the task
// succeeded (object within 0.05 m of the goal at the last step), 0 otherwise.

#include <array>
#include <cstdint>
#include <vector>

#include "common/rng.h"
#include "rl/choreographer_net.h"
#include "sim/environment.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

struct HlcDecision {
  int choice = 0;
  std::array<double, sim::kNumSubtasks> probabilities{};
  double value = 0;
  double reward = 0;
  int steps = 0;           // environment steps the chosen expert ran
  bool exploring = false;  // drawn uniformly (an exploring start), not from the policy
};

struct HlcEpisode {
  std::vector<HlcDecision> decisions;
  std::vector<DecisionCache> caches;           // for back-propagation (training only)
  std::vector<sim::Observation> observations;  // the decision inputs, for the normaliser
  // The goal they were made for: after a physics fault the environment has already begun
  // the next episode, whose goal episode_goal() then returns.
  sim::Goal goal = sim::Goal::Zero();
  bool success = false;
  int env_steps = 0;
};

// The subtasks the choreographer may choose from in this state: those whose termination
// predicate does not already hold (an option is available only where it would not end
// at once, as in the options framework's initiation sets). Without this the sampled
// policy spent decisions re-running a finished subtask for one step ("AAR": approach
// twice, then retract without a grasp), and those episodes' failures were charged to
// the good first choice. Any order of the remaining subtasks stays possible.
// mask_finished false (the paper's choreographer): every subtask, always.
std::array<bool, sim::kNumSubtasks> available_subtasks(const sim::TaskState& state,
                                                       bool mask_finished);

// Softmax of the choreographer's logits over the available subtasks; the others get
// probability 0.
std::array<double, sim::kNumSubtasks> masked_softmax(
    const std::array<double, sim::kNumSubtasks>& logits,
    const std::array<bool, sim::kNumSubtasks>& available);

// The choreographer's choice probabilities in this state: its logits plus the chain prior
// (ChoreographerSpec::chain_prior), softmaxed over the available subtasks. Training,
// evaluation and serving all decide through this.
std::array<double, sim::kNumSubtasks> decision_probabilities(
    std::array<double, sim::kNumSubtasks> logits, const sim::TaskState& state,
    const ChoreographerSpec& spec);

// A draw from `p` (masked_softmax's output) when sampling, else the most probable; never a
// subtask of probability 0.
int choose_subtask(const std::array<double, sim::kNumSubtasks>& p, bool sample, Rng& rng);

// A draw of one of the available subtasks, each as likely (an exploring start).
int choose_uniformly(const std::array<bool, sim::kNumSubtasks>& available, Rng& rng);

// sample: draw choices from the policy (training); otherwise take the most probable.
// explore_first: the first choice is drawn by choose_uniformly instead (training only).
HlcEpisode run_hlc_episode(sim::Environment& env, ChoreographerNet& net,
                           const std::array<sim::SubtaskPolicy*, sim::kNumSubtasks>& experts,
                           std::uint64_t episode_seed, bool sample, Rng& choice_rng,
                           bool explore_first = false);

}  // namespace pnp::rl
