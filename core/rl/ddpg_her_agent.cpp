#include "rl/ddpg_her_agent.h"

#include <algorithm>
#include <array>

#include "nn/flat_ops.h"

namespace pnp::rl {
namespace {

constexpr int kObs = sim::kObservationSize;
constexpr int kGoal = sim::kGoalSize;
constexpr int kAct = sim::kActionSize;

nn::MlpSpec actor_spec(const DdpgHerConfig& c) {
  return {kPolicyInputs, c.hidden, kAct, c.hidden_activation, nn::Activation::kTanh};
}
nn::MlpSpec critic_spec(const DdpgHerConfig& c) {
  return {kPolicyInputs + kAct, c.hidden, 1, c.hidden_activation, nn::Activation::kNone};
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

struct DdpgHerAgent::Partition {
  Eigen::Index begin = 0, count = 0;
  nn::Matrix state, next_state, critic_in, next_critic_in, target, dq, dx, da, demo_state, demo_da;
  nn::MlpWorkspace actor_ws, critic_ws, target_actor_ws, target_critic_ws, demo_ws;
  nn::AlignedFloats actor_grads, critic_grads;
  double critic_loss = 0, q_sum = 0, motion_sq = 0, commitment = 0, bc_sq = 0;
};

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

DdpgHerAgent::DdpgHerAgent(const DdpgHerConfig& config, Rng& init_rng, std::size_t update_threads)
    : config_((config.validate(), config)),
      actor_(actor_spec(config_)),
      critic_(critic_spec(config_)),
      actor_target_(actor_spec(config_)),
      critic_target_(critic_spec(config_)),
      obs_norm_(kObs, config_.norm_clip, config_.norm_std_floor),
      goal_norm_(kGoal, config_.norm_clip, config_.norm_std_floor),
      actor_adam_(actor_.params().size(), {config_.actor_learning_rate}),
      critic_adam_(critic_.params().size(), {config_.critic_learning_rate}),
      pool_(update_threads) {
  actor_.initialise(init_rng);
  critic_.initialise(init_rng);
  sync_targets();
  parts_.resize(kUpdatePartitions);
  for (Partition& p : parts_) {
    p.actor_grads.assign(actor_.params().size(), 0.0f);
    p.critic_grads.assign(critic_.params().size(), 0.0f);
  }
}

DdpgHerAgent::~DdpgHerAgent() = default;

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

namespace {

// Column range of partition p of n samples.
std::pair<Eigen::Index, Eigen::Index> columns(int p, Eigen::Index n) {
  const Eigen::Index begin = n * p / kUpdatePartitions, end = n * (p + 1) / kUpdatePartitions;
  return {begin, end - begin};
}

// Slice k of n parameters, for the element-wise steps (gradient sum, Adam, Polyak); slices
// begin on nn::kSliceAlignment, so they give the unsplit step's exact result.
std::pair<std::size_t, std::size_t> slice(std::size_t k, std::size_t n) {
  const std::size_t parts = kUpdatePartitions, a = nn::kSliceAlignment;
  const auto boundary = [&](std::size_t i) {
    return i == parts ? n : std::min(n, n * i / parts / a * a);
  };
  return {boundary(k), boundary(k + 1) - boundary(k)};
}

}  // namespace

void DdpgHerAgent::normalise_columns(const std::vector<float>& observations,
                                     const std::vector<float>& goals, Eigen::Index begin,
                                     Eigen::Index count, nn::Matrix& states) const {
  nn::ensure_shape(states, kPolicyInputs, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    normalise_rows(obs_norm_, config_.clip_obs, observations.data() + (begin + i) * kObs, states, 0,
                   i);
    normalise_rows(goal_norm_, config_.clip_obs, goals.data() + (begin + i) * kGoal, states, kObs,
                   i);
  }
}

void DdpgHerAgent::gradients(const SampledBatch& batch, Eigen::Index total, Partition& p) const {
  const Eigen::Index c = p.count;
  normalise_columns(batch.observation, batch.goal, p.begin, c, p.state);
  normalise_columns(batch.next_observation, batch.goal, p.begin, c, p.next_state);
  // Target: r + gamma (1 - done) Q'(s', pi'(s')), clamped to [-1/(1-gamma), 0].
  const nn::Matrix& next_action = actor_target_.forward(p.next_state, p.target_actor_ws);
  nn::ensure_shape(p.next_critic_in, kPolicyInputs + kAct, c);
  p.next_critic_in.topRows(kPolicyInputs) = p.next_state;
  p.next_critic_in.bottomRows(kAct) = next_action;
  const nn::Matrix& next_q = critic_target_.forward(p.next_critic_in, p.target_critic_ws);
  nn::ensure_shape(p.target, 1, c);
  const auto gamma = static_cast<float>(config_.gamma);
  const auto clip_return = static_cast<float>(-1.0 / (1.0 - config_.gamma));
  for (Eigen::Index i = 0; i < c; ++i) {
    const auto k = static_cast<std::size_t>(p.begin + i);
    p.target(0, i) = std::clamp(batch.reward[k] + gamma * (1.0f - batch.done[k]) * next_q(0, i),
                                clip_return, 0.0f);
  }
  // One critic pass over 2c samples: [s, a] (the critic's loss) then [s, pi(s)] (the
  // actor's), both with the critic's current parameters, as in the original code, which
  // computes both losses before applying either step.
  const nn::Matrix& pi = actor_.forward(p.state, p.actor_ws);
  nn::ensure_shape(p.critic_in, kPolicyInputs + kAct, 2 * c);
  p.critic_in.topLeftCorner(kPolicyInputs, c) = p.state;
  p.critic_in.topRightCorner(kPolicyInputs, c) = p.state;
  for (Eigen::Index i = 0; i < c; ++i) {
    for (int a = 0; a < kAct; ++a) {
      p.critic_in(kPolicyInputs + a, i) =
          batch.action[static_cast<std::size_t>((p.begin + i) * kAct + a)];
    }
  }
  p.critic_in.bottomRightCorner(kAct, c) = pi;
  const nn::Matrix& q = critic_.forward(p.critic_in, p.critic_ws);
  // Critic: mean squared error over the whole batch. Actor: maximise Q(s, pi(s)).
  nn::ensure_shape(p.dq, 1, 2 * c);
  p.dq.leftCols(c) = (q.leftCols(c) - p.target) * (2.0f / static_cast<float>(total));
  p.dq.rightCols(c).setConstant(-1.0f / static_cast<float>(total));
  p.critic_loss = static_cast<double>((q.leftCols(c) - p.target).squaredNorm());
  p.q_sum = static_cast<double>(q.rightCols(c).sum());
  std::fill(p.critic_grads.begin(), p.critic_grads.end(), 0.0f);
  critic_.backward_into(p.critic_ws, p.dq, p.critic_grads, &p.dx, c);
  // The L2 penalty applies to the motion (xyz) only: a held grasp needs a gripper command
  // near -1, and penalising it trained the actor to let go (measured: retract with a
  // learned gripper stayed under 10% task success).
  const auto motion = pi.topRows(3);
  p.motion_sq = static_cast<double>(motion.squaredNorm());
  const auto l2 = static_cast<float>(config_.action_l2);
  const auto motion_size = static_cast<float>(3 * total);
  p.da = p.dx.bottomRightCorner(kAct, c);
  p.da.topRows(3) += motion * (2.0f * l2 / motion_size);
  p.commitment = 0;
  if (config_.learn_gripper && config_.gripper_commitment > 0) {
    // Closing commands only: pushing an opening one open could freeze the fingers open.
    const float scale =
        2.0f * static_cast<float>(config_.gripper_commitment) / static_cast<float>(total);
    for (Eigen::Index i = 0; i < c; ++i) {
      const float g = pi(3, i);
      if (g >= 0) continue;
      p.commitment += static_cast<double>(1.0f - g * g);
      p.da(3, i) -= g * scale;
    }
  }
  std::fill(p.actor_grads.begin(), p.actor_grads.end(), 0.0f);
  actor_.backward_into(p.actor_ws, p.da, p.actor_grads, nullptr);
}

double DdpgHerAgent::bc_gradient(const SampledBatch& demos, Eigen::Index begin, Eigen::Index count,
                                 Eigen::Index total, float weight, Partition& p) const {
  normalise_columns(demos.observation, demos.goal, begin, count, p.demo_state);
  const nn::Matrix& pi = actor_.forward(p.demo_state, p.demo_ws);
  nn::ensure_shape(p.demo_da, kAct, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    for (int a = 0; a < kAct; ++a) {
      p.demo_da(a, i) = pi(a, i) - demos.action[static_cast<std::size_t>((begin + i) * kAct + a)];
    }
  }
  const double squared_error = static_cast<double>(p.demo_da.squaredNorm());
  p.demo_da *= 2.0f * weight / static_cast<float>(total * kAct);
  actor_.backward_into(p.demo_ws, p.demo_da, p.actor_grads, nullptr);
  return squared_error;
}

void DdpgHerAgent::step_networks(bool critic_too) {
  actor_adam_.begin_step();
  if (critic_too) critic_adam_.begin_step();
  pool_.parallel_for(parts_.size(), [&](std::size_t k) {
    const auto step = [&](nn::Mlp& net, nn::Adam& adam, bool actor) {
      // The partitions' gradients, summed by Adam in partition order: never by timing.
      std::array<std::span<const float>, kUpdatePartitions> partials;
      for (std::size_t i = 0; i < parts_.size(); ++i)
        partials[i] = actor ? parts_[i].actor_grads : parts_[i].critic_grads;
      const auto [begin, count] = slice(k, net.params().size());
      adam.apply(net.params(), partials, begin, count);
    };
    if (critic_too) step(critic_, critic_adam_, false);
    step(actor_, actor_adam_, true);
  });
}

UpdateStats DdpgHerAgent::update(const SampledBatch& batch, const SampledBatch* demos) {
  const auto n = static_cast<Eigen::Index>(batch.reward.size());
  const bool with_demos = demos && config_.demo_bc_weight > 0;
  const auto demo_n = with_demos ? static_cast<Eigen::Index>(demos->reward.size()) : 0;
  for (int k = 0; k < kUpdatePartitions; ++k)
    std::tie(parts_[static_cast<std::size_t>(k)].begin, parts_[static_cast<std::size_t>(k)].count) =
        columns(k, n);

  pool_.parallel_for(parts_.size(), [&](std::size_t k) {
    Partition& p = parts_[k];
    gradients(batch, n, p);
    p.bc_sq = 0;
    if (with_demos) {
      const auto [begin, count] = columns(static_cast<int>(k), demo_n);
      p.bc_sq =
          bc_gradient(*demos, begin, count, demo_n, static_cast<float>(config_.demo_bc_weight), p);
    }
  });
  step_networks(true);

  UpdateStats stats;
  double q = 0, motion = 0, commitment = 0, bc = 0;
  for (const Partition& p : parts_) {
    stats.critic_loss += p.critic_loss;
    q += p.q_sum;
    motion += p.motion_sq;
    commitment += p.commitment;
    bc += p.bc_sq;
  }
  stats.critic_loss /= static_cast<double>(n);
  stats.mean_q = q / static_cast<double>(n);
  stats.actor_loss = -stats.mean_q + config_.action_l2 * motion / static_cast<double>(3 * n) +
                     config_.gripper_commitment * commitment / static_cast<double>(n);
  if (with_demos) stats.bc_loss = bc / static_cast<double>(demo_n * kAct);
  return stats;
}

double DdpgHerAgent::behaviour_clone(const SampledBatch& batch) {
  const auto n = static_cast<Eigen::Index>(batch.reward.size());
  pool_.parallel_for(parts_.size(), [&](std::size_t k) {
    Partition& p = parts_[k];
    std::fill(p.actor_grads.begin(), p.actor_grads.end(), 0.0f);
    const auto [begin, count] = columns(static_cast<int>(k), n);
    p.bc_sq = bc_gradient(batch, begin, count, n, 1.0f, p);
  });
  step_networks(false);
  double squared = 0;
  for (const Partition& p : parts_) squared += p.bc_sq;
  return squared / static_cast<double>(n * kAct);
}

void DdpgHerAgent::update_targets(int gradient_steps) {
  const double polyak = target_coefficient(config_, gradient_steps);
  pool_.parallel_for(parts_.size(), [&](std::size_t k) {
    for (auto [target, online] :
         {std::pair{&actor_target_, &actor_}, {&critic_target_, &critic_}}) {
      const auto [begin, count] = slice(k, online->params().size());
      nn::polyak_update(target->params().subspan(begin, count),
                        std::span<const float>(online->params()).subspan(begin, count), polyak);
    }
  });
}

}  // namespace pnp::rl
