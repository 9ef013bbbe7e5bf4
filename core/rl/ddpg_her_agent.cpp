#include "rl/ddpg_her_agent.h"

#include <algorithm>

#include "nn/flat_ops.h"

namespace pnp::rl {
namespace {

constexpr int kObs = sim::kObservationSize;
constexpr int kGoal = sim::kGoalSize;
constexpr int kAct = sim::kActionSize;

nn::MlpSpec actor_spec(const DdpgHerConfig& c) {
  return {kPolicyInputs, c.hidden, kAct, nn::Activation::kReLU, nn::Activation::kTanh};
}
nn::MlpSpec critic_spec(const DdpgHerConfig& c) {
  return {kPolicyInputs + kAct, c.hidden, 1, nn::Activation::kReLU, nn::Activation::kNone};
}

// Normalises one column of raw float inputs (observation or goal) in place.
void normalise_rows(const nn::Normalizer& norm, double clip_raw, const float* raw, nn::Matrix& out,
                    Eigen::Index row, Eigen::Index col) {
  const auto mean = norm.mean();
  const auto std = norm.stddev();
  const auto c = static_cast<float>(norm.clip());
  const auto clip = static_cast<float>(clip_raw);
  for (std::size_t k = 0; k < mean.size(); ++k) {
    const float x = std::clamp(raw[k], -clip, clip);
    out(row + static_cast<Eigen::Index>(k), col) = std::clamp((x - mean[k]) / std[k], -c, c);
  }
}

}  // namespace

void normalise_policy_input(const nn::Normalizer& obs_norm, const nn::Normalizer& goal_norm,
                            double clip_obs, const sim::Observation& observation,
                            const sim::Goal& goal, nn::Matrix& out, Eigen::Index col) {
  float raw[kObs];
  for (int k = 0; k < kObs; ++k) raw[k] = static_cast<float>(observation(k));
  normalise_rows(obs_norm, clip_obs, raw, out, 0, col);
  float g[kGoal];
  for (int k = 0; k < kGoal; ++k) g[k] = static_cast<float>(goal(k));
  normalise_rows(goal_norm, clip_obs, g, out, kObs, col);
}

ActorSnapshot::ActorSnapshot(const nn::Mlp& actor, const nn::Normalizer& obs_norm,
                             const nn::Normalizer& goal_norm, double clip_obs)
    : actor_(actor),
      obs_norm_(obs_norm),
      goal_norm_(goal_norm),
      clip_obs_(clip_obs),
      input_(kPolicyInputs, 1) {}

sim::Action ActorSnapshot::act(const sim::Observation& observation, const sim::Goal& goal) {
  normalise_policy_input(obs_norm_, goal_norm_, clip_obs_, observation, goal, input_, 0);
  const nn::Matrix& out = actor_.forward(input_, workspace_);
  return out.col(0).cast<double>();
}

DdpgHerAgent::DdpgHerAgent(const DdpgHerConfig& config, Rng& init_rng)
    : config_((config.validate(), config)),
      actor_(actor_spec(config_)),
      critic_(critic_spec(config_)),
      actor_target_(actor_spec(config_)),
      critic_target_(critic_spec(config_)),
      obs_norm_(kObs, config_.norm_clip, config_.norm_std_floor),
      goal_norm_(kGoal, config_.norm_clip, config_.norm_std_floor),
      actor_adam_(actor_.params().size(), {config_.actor_learning_rate}),
      critic_adam_(critic_.params().size(), {config_.critic_learning_rate}) {
  actor_.initialise(init_rng);
  critic_.initialise(init_rng);
  sync_targets();
}

void DdpgHerAgent::sync_targets() {
  nn::copy_into(actor_target_.params(), actor_.params());
  nn::copy_into(critic_target_.params(), critic_.params());
}

ActorSnapshot DdpgHerAgent::snapshot() const {
  return ActorSnapshot(actor_, obs_norm_, goal_norm_, config_.clip_obs);
}

void DdpgHerAgent::update_normalizers(std::span<const sim::Observation> observations,
                                      std::span<const sim::Goal> goals) {
  for (const auto& o : observations) {
    const sim::Observation clipped = o.cwiseMax(-config_.clip_obs).cwiseMin(config_.clip_obs);
    obs_norm_.update(std::span<const double>(clipped.data(), kObs));
  }
  for (const auto& g : goals) goal_norm_.update(std::span<const double>(g.data(), kGoal));
  obs_norm_.refresh();
  goal_norm_.refresh();
}

void DdpgHerAgent::normalise_states(const SampledBatch& batch, nn::Matrix& states) const {
  const auto n = static_cast<Eigen::Index>(batch.reward.size());
  nn::ensure_shape(states, kPolicyInputs, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    normalise_rows(obs_norm_, config_.clip_obs, batch.observation.data() + i * kObs, states, 0, i);
    normalise_rows(goal_norm_, config_.clip_obs, batch.goal.data() + i * kGoal, states, kObs, i);
  }
}

void DdpgHerAgent::prepare_inputs(const SampledBatch& batch) {
  normalise_states(batch, state_);
  const auto n = static_cast<Eigen::Index>(batch.reward.size());
  nn::ensure_shape(next_state_, kPolicyInputs, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    normalise_rows(obs_norm_, config_.clip_obs, batch.next_observation.data() + i * kObs, next_state_, 0, i);
    normalise_rows(goal_norm_, config_.clip_obs, batch.goal.data() + i * kGoal, next_state_, kObs, i);
  }
}

double DdpgHerAgent::accumulate_bc_gradient(const SampledBatch& demos, float weight) {
  normalise_states(demos, demo_state_);
  const auto n = demo_state_.cols();
  const nn::Matrix& pi = actor_.forward(demo_state_, demo_ws_);
  nn::ensure_shape(demo_da_, kAct, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int a = 0; a < kAct; ++a) demo_da_(a, i) = pi(a, i) - demos.action[static_cast<std::size_t>(i * kAct + a)];
  }
  const double loss = static_cast<double>(demo_da_.squaredNorm()) / static_cast<double>(demo_da_.size());
  demo_da_ *= 2.0f * weight / static_cast<float>(demo_da_.size());
  actor_.backward(demo_ws_, demo_da_, true, nullptr);
  return loss;
}

UpdateStats DdpgHerAgent::update(const SampledBatch& batch, const SampledBatch* demos) {
  prepare_inputs(batch);
  const auto n = state_.cols();
  const float inv_n = 1.0f / static_cast<float>(n);
  UpdateStats stats;

  // Critic target: r + gamma (1 - done) Q'(s', pi'(s')), clamped.
  const nn::Matrix& next_action = actor_target_.forward(next_state_, target_actor_ws_);
  nn::ensure_shape(next_critic_in_, kPolicyInputs + kAct, n);
  next_critic_in_.topRows(kPolicyInputs) = next_state_;
  next_critic_in_.bottomRows(kAct) = next_action;
  const nn::Matrix& next_q = critic_target_.forward(next_critic_in_, target_critic_ws_);
  nn::ensure_shape(target_, 1, n);
  const auto gamma = static_cast<float>(config_.gamma);
  const auto clip_return = static_cast<float>(-1.0 / (1.0 - config_.gamma));
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const float y = batch.reward[k] + gamma * (1.0f - batch.done[k]) * next_q(0, i);
    target_(0, i) = std::clamp(y, clip_return, 0.0f);
  }

  // Critic: mean squared error to the target.
  nn::ensure_shape(critic_in_, kPolicyInputs + kAct, n);
  critic_in_.topRows(kPolicyInputs) = state_;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int a = 0; a < kAct; ++a)
      critic_in_(kPolicyInputs + a, i) = batch.action[static_cast<std::size_t>(i * kAct + a)];
  }
  const nn::Matrix& q = critic_.forward(critic_in_, critic_ws_);
  dq_ = (q - target_) * (2.0f * inv_n);
  stats.critic_loss = static_cast<double>((q - target_).squaredNorm() * inv_n);
  critic_.zero_grads();
  critic_.backward(critic_ws_, dq_, true, nullptr);
  critic_adam_.step(critic_.params(), critic_.grads());

  // Actor: maximise Q(s, pi(s)) with an L2 penalty on the actions.
  const nn::Matrix& pi = actor_.forward(state_, actor_ws_);
  critic_in_.bottomRows(kAct) = pi;
  const nn::Matrix& q_pi = critic_.forward(critic_in_, critic_pi_ws_);
  stats.mean_q = static_cast<double>(q_pi.mean());
  // The L2 penalty applies to the motion (xyz) only: a held grasp needs a gripper
  // command near -1, and penalising it trained the actor to let go (measured: retract
  // with a learned gripper stayed under 10% task success).
  const auto l2 = static_cast<float>(config_.action_l2);
  const auto motion = pi.topRows(3);
  const auto motion_size = static_cast<float>(motion.size());
  stats.actor_loss = static_cast<double>(-q_pi.mean() + l2 * motion.squaredNorm() / motion_size);
  dq_.setConstant(1, n, -inv_n);
  critic_.backward(critic_pi_ws_, dq_, false, &dx_);  // dQ/d(input); the critic's grads untouched
  da_ = dx_.bottomRows(kAct);
  da_.topRows(3) += motion * (2.0f * l2 / motion_size);
  actor_.zero_grads();
  actor_.backward(actor_ws_, da_, true, nullptr);
  if (demos && config_.demo_bc_weight > 0) {
    stats.bc_loss = accumulate_bc_gradient(*demos, static_cast<float>(config_.demo_bc_weight));
  }
  actor_adam_.step(actor_.params(), actor_.grads());
  return stats;
}

double DdpgHerAgent::behaviour_clone(const SampledBatch& batch) {
  actor_.zero_grads();
  const double loss = accumulate_bc_gradient(batch, 1.0f);
  actor_adam_.step(actor_.params(), actor_.grads());
  return loss;
}

void DdpgHerAgent::update_targets() {
  nn::polyak_update(actor_target_.params(), actor_.params(), config_.polyak);
  nn::polyak_update(critic_target_.params(), critic_.params(), config_.polyak);
}

}  // namespace pnp::rl
