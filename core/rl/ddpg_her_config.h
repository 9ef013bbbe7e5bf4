#pragma once
// Every DDPG+HER hyperparameter in one struct. Defaults are the original code's
// (../shared/reference/original-implementation.md), except where a comment says why.

#include <vector>

#include "nn/activation.h"
#include "sim/gripper_script.h"

namespace pnp::rl {

struct DdpgHerConfig {
  std::vector<int> hidden{256, 256, 256};                    // actor and critic hidden widths
  nn::Activation hidden_activation = nn::Activation::kReLU;  // the original BC used ELU
  double actor_learning_rate = 1e-3;
  double critic_learning_rate = 1e-3;
  double gamma = 0.98;
  double polyak = 0.95;  // target <- polyak target + (1 - polyak) online
  int batch_size = 256;
  long long buffer_size = 1'000'000;  // transitions
  int her_k = 4;                      // relabelled : original goals = k : 1 ("future")
  double noise_eps = 0.2;             // Gaussian action noise sigma
  double random_eps = 0.3;            // probability of a uniformly random action
  bool random_gripper = false;        // random actions include the gripper (see subtask_rollout.h)
  double action_l2 = 1.0;             // penalty on the actor's squared motion (xyz, not gripper)
  // Weight of a prior on a learned gripper command g: gripper_commitment * mean over the
  // batch of (1 - g^2) where g < 0 (a closing command is pushed to -1; an opening one is
  // left to the critic). The environment's finger servo saturates (gym: ctrl = q + a metres), so
  // every g < 0 squeezes alike and the critic is flat there: nothing held a retract's command away
  // from 0, it drifted there in states training had not covered, crossed it and let go
  // (every failure of a cylinder retract traced on the Panda). A two-sided prior (to
  // whichever end g was on) froze a fresh retract's fingers open: 0.13 at 34k steps
  // (Panda, gym world, seed 0). Subtask training applies it to retract only
  // (rl/subtask_trainer.h agent_config): approach and manipulate must find when to open
  // and close, and with the prior an approach expert's closed fingers froze shut (measured:
  // 0% approach success at 15k steps, gym world, Panda, seed 100).
  double gripper_commitment = 0;
  double clip_obs = 200.0;  // observations clipped before normalising
  double norm_clip = 5.0;
  double norm_std_floor = 0.01;
  int episodes_per_cycle = 2;  // rollouts between two rounds of updates
  int updates_per_cycle = 40;  // gradient steps per cycle; targets updated once per cycle
  // How fast the targets follow, per gradient step. 0: once per cycle by `polyak`,
  // whatever the cycle's number of gradient steps (the original, whose cycles all have 40).
  // n > 0: at the rate of `polyak` per n gradient steps, so a cycle of u steps moves them
  // with polyak^(u / n). With updates_per_transition, a cycle's steps follow its segments'
  // lengths (an approach cycle gets ~10), and per cycle the targets would move 4x faster
  // per gradient step than the original's; n = 40 keeps the original's rate.
  int polyak_every_updates = 0;
  // > 0: a cycle's gradient steps are this many per transition it stored instead of
  // updates_per_cycle (the original's 40 per 2 x 50 steps is 0.4). Subtask segments are
  // short (an approach ends in ~10 steps), so a fixed 40 per cycle spends several updates
  // on every new transition, and the wall time with them.
  double updates_per_transition = 0;
  bool learn_gripper = true;  // false: the gripper command stays scripted (paper-faithful)
  // Which script commands it then (sim/gripper_script.h).
  sim::GripperScript gripper_script = sim::GripperScript::kGraspRule;
  // Learning from demonstrations: before exploring, run this many scripted episodes of
  // the subtask (their steps count as training steps), store them in the replay, and
  // pretrain the actor on them by behaviour cloning. Without it the untrained actor's
  // gripper command (about 0) holds nothing, and retract never keeps hold of the object.
  int demo_episodes = 10;
  int demo_pretrain_updates = 300;
  // Weight of a behaviour-cloning term on demonstration samples in every actor update
  // (Nair et al. 2018). Without it hindsight relabelling teaches retract to let go: after
  // a drop the object rests where it fell, so relabelled goals make opening look like an
  // instant success (measured: the learned gripper command went to +1, fully open).
  double demo_bc_weight = 5.0;  // retract: 98% task success at 5k steps (1.0: 30-66%)
  int demo_batch_size = 64;

  // Throws INVALID_ARGUMENT naming the field and the expected value.
  void validate() const;
};

// The Polyak coefficient for a round of `gradient_steps` steps (see polyak_every_updates).
double target_coefficient(const DdpgHerConfig& config, int gradient_steps);

// The original code's behaviour-cloning networks and schedule, for the paper-faithful BC
// row: 2 x 128 ELU, Adam 1e-4, one gradient step per environment step on one labelled
// state (here drawn from the labelled replay). The original's Gaussian heads are not
// reproduced: the learner explores with base's action noise, as every expert here does.
DdpgHerConfig original_bc_config(DdpgHerConfig base);

}  // namespace pnp::rl
