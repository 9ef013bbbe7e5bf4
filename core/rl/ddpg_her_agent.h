#pragma once
// DDPG with hindsight experience replay for one goal-conditioned expert.
//
// Actor:  [normalised observation (25), normalised goal (3)] -> hidden (ReLU by default) -> 4,
// tanh. Critic: [normalised observation, normalised goal, action (4)] -> hidden (same activation)
// -> 1. Critic target r + gamma (1 - done) Q'(s', pi'(s')), clamped to [-1/(1-gamma), 0] (the
// rewards are minus distances); actor loss -Q(s, pi(s)) + action_l2 * mean(motion^2)
// + gripper_commitment * mean((1 - gripper^2) where gripper < 0) (ddpg_her_config.h).

#include <span>

#include "common/rng.h"
#include "common/thread_pool.h"
#include "nn/adam.h"
#include "nn/mlp.h"
#include "nn/normalizer.h"
#include "rl/ddpg_her_config.h"
#include "rl/segment_replay.h"
#include "sim/observation.h"

namespace pnp::rl {

inline constexpr int kPolicyInputs = sim::kObservationSize + sim::kGoalSize;

struct UpdateStats {
  double critic_loss = 0;
  double actor_loss = 0;
  double mean_q = 0;
  double bc_loss = 0;
};

// What acting needs: the actor and the input normalisers. Copyable, so each rollout or
// evaluation worker holds its own (the workspace is per copy).
class ActorSnapshot {
 public:
  ActorSnapshot(const nn::Mlp& actor, const nn::Normalizer& obs_norm,
                const nn::Normalizer& goal_norm, double clip_obs);
  // Deterministic action in [-1, 1]^4.
  sim::Action act(const sim::Observation& observation, const sim::Goal& goal);
  const nn::Mlp& actor() const { return actor_; }
  const nn::Normalizer& observation_normalizer() const { return obs_norm_; }
  const nn::Normalizer& goal_normalizer() const { return goal_norm_; }
  double clip_obs() const { return clip_obs_; }

 private:
  nn::Mlp actor_;
  nn::Normalizer obs_norm_, goal_norm_;
  double clip_obs_;
  nn::Matrix input_;
  nn::MlpWorkspace workspace_;
};

// Writes the clipped, normalised [observation; goal] into column `col` of `out`.
void normalise_policy_input(const nn::Normalizer& obs_norm, const nn::Normalizer& goal_norm,
                            double clip_obs, const sim::Observation& observation,
                            const sim::Goal& goal, nn::Matrix& out, Eigen::Index col);

// The update splits each batch into this many fixed column ranges, back-propagated in
// parallel and summed in a fixed order: the result is the same whatever the number of
// threads (with one, the ranges run in turn).
inline constexpr int kUpdatePartitions = 2;

class DdpgHerAgent {
 public:
  // update_threads: threads for the update's partitions (the result does not depend on it).
  DdpgHerAgent(const DdpgHerConfig& config, Rng& init_rng,
               std::size_t update_threads = kUpdatePartitions);
  ~DdpgHerAgent();
  DdpgHerAgent(const DdpgHerAgent&) = delete;
  DdpgHerAgent& operator=(const DdpgHerAgent&) = delete;

  const DdpgHerConfig& config() const { return config_; }
  ActorSnapshot snapshot() const;

  // Adds observations and goals to the normalisers' statistics, then publishes them.
  void update_normalizers(std::span<const sim::Observation> observations,
                          std::span<const sim::Goal> goals);

  // One gradient step on the critic and the actor from a batch. With `demos`, the
  // actor's loss also has demo_bc_weight x the mean squared error to the demonstrated
  // actions on that batch.
  UpdateStats update(const SampledBatch& batch, const SampledBatch* demos = nullptr);
  // Polyak averaging after a round of `gradient_steps` updates (rl::target_coefficient).
  void update_targets(int gradient_steps);
  // One behaviour-cloning step on the actor: mean squared error to the batch's actions
  // (for demonstrations the batch is sampled without relabelling). Returns the loss.
  double behaviour_clone(const SampledBatch& batch);

  nn::Mlp& actor() { return actor_; }
  nn::Mlp& critic() { return critic_; }
  const nn::Mlp& actor() const { return actor_; }
  const nn::Mlp& critic() const { return critic_; }
  const nn::Normalizer& observation_normalizer() const { return obs_norm_; }
  const nn::Normalizer& goal_normalizer() const { return goal_norm_; }
  nn::Normalizer& observation_normalizer() { return obs_norm_; }
  nn::Normalizer& goal_normalizer() { return goal_norm_; }
  // After restoring weights (fine-tuning from a checkpoint): targets := online.
  void sync_targets();

 private:
  struct Partition;
  // Normalised [observation; goal] of columns [begin, begin + count) of a batch.
  void normalise_columns(const std::vector<float>& observations, const std::vector<float>& goals,
                         Eigen::Index begin, Eigen::Index count, nn::Matrix& states) const;
  // Both gradients of one partition from one critic pass over [Q(s, a) | Q(s, pi(s))].
  void gradients(const SampledBatch& batch, Eigen::Index total, Partition& p) const;
  // Adds weight x the BC gradient of columns [begin, begin + count) of `demos` (mean over
  // `total` samples) to p.actor_grads; returns that part's squared-error sum.
  double bc_gradient(const SampledBatch& demos, Eigen::Index begin, Eigen::Index count,
                     Eigen::Index total, float weight, Partition& p) const;
  // Sums the partitions' gradients and takes the Adam step of the actor (and the critic),
  // each thread on its own slice of the parameters: element-wise, so the result does not
  // depend on the split.
  void step_networks(bool critic_too);

  DdpgHerConfig config_;
  nn::Mlp actor_, critic_, actor_target_, critic_target_;
  nn::Normalizer obs_norm_, goal_norm_;
  nn::Adam actor_adam_, critic_adam_;
  // Preallocated per-partition buffers and workspaces: a steady batch size never allocates.
  std::vector<Partition> parts_;
  ThreadPool pool_;
};

}  // namespace pnp::rl
