#include "rl/ddpg_her_config.h"

#include <cmath>
#include <string>

#include "common/error.h"
#include "rl/network_limits.h"
#include "sim/observation.h"

namespace pnp::rl {
namespace {

void require(bool ok, const char* field, const char* expected, double got) {
  if (!ok) throw_invalid_argument(field, expected, std::to_string(got));
}

}  // namespace

void DdpgHerConfig::validate() const {
  // The critic is the larger network: observation, goal and action in, one value out.
  check_layer_widths("hidden", hidden, sim::kObservationSize + sim::kGoalSize + sim::kActionSize,
                     1);
  if (hidden_activation != nn::Activation::kReLU && hidden_activation != nn::Activation::kELU &&
      hidden_activation != nn::Activation::kTanh) {
    throw_invalid_argument("hidden_activation", "relu, elu or tanh",
                           std::string(nn::activation_name(hidden_activation)));
  }
  require(actor_learning_rate > 0 && std::isfinite(actor_learning_rate), "actor_learning_rate",
          "a positive finite number", actor_learning_rate);
  require(critic_learning_rate > 0 && std::isfinite(critic_learning_rate), "critic_learning_rate",
          "a positive finite number", critic_learning_rate);
  require(gamma > 0 && gamma < 1, "gamma", "a value in (0, 1)", gamma);
  require(polyak >= 0 && polyak < 1, "polyak", "a value in [0, 1)", polyak);
  if (batch_size <= 0 || batch_size > kMaxBatchSize) {
    throw_invalid_argument("batch_size", "1 to " + std::to_string(kMaxBatchSize),
                           std::to_string(batch_size));
  }
  require(buffer_size > 0, "buffer_size", "a positive integer", static_cast<double>(buffer_size));
  if (batch_size > buffer_size) {
    throw_invalid_argument("batch_size",
                           "at most buffer_size (" + std::to_string(buffer_size) + ")",
                           std::to_string(batch_size));
  }
  require(her_k >= 0, "her_k", "a non-negative integer", her_k);
  require(noise_eps >= 0 && std::isfinite(noise_eps), "noise_eps", "a non-negative number",
          noise_eps);
  require(random_eps >= 0 && random_eps <= 1, "random_eps", "a probability in [0, 1]", random_eps);
  require(action_l2 >= 0 && std::isfinite(action_l2), "action_l2", "a non-negative number",
          action_l2);
  require(gripper_commitment >= 0 && std::isfinite(gripper_commitment), "gripper_commitment",
          "a non-negative number", gripper_commitment);
  require(clip_obs > 0, "clip_obs", "a positive number", clip_obs);
  require(norm_clip > 0, "norm_clip", "a positive number", norm_clip);
  require(norm_std_floor > 0, "norm_std_floor", "a positive number", norm_std_floor);
  require(episodes_per_cycle > 0, "episodes_per_cycle", "a positive integer", episodes_per_cycle);
  require(updates_per_cycle >= 0, "updates_per_cycle", "a non-negative integer", updates_per_cycle);
  require(updates_per_transition >= 0 && std::isfinite(updates_per_transition),
          "updates_per_transition", "a non-negative number (0: updates_per_cycle)",
          updates_per_transition);
  require(polyak_every_updates >= 0, "polyak_every_updates",
          "a non-negative integer (0: once per cycle)", polyak_every_updates);
  require(demo_episodes >= 0, "demo_episodes", "a non-negative integer", demo_episodes);
  require(demo_pretrain_updates >= 0, "demo_pretrain_updates", "a non-negative integer",
          demo_pretrain_updates);
  require(demo_bc_weight >= 0 && std::isfinite(demo_bc_weight), "demo_bc_weight",
          "a non-negative number", demo_bc_weight);
  require(demo_batch_size > 0, "demo_batch_size", "a positive integer", demo_batch_size);
}

double target_coefficient(const DdpgHerConfig& config, int gradient_steps) {
  if (config.polyak_every_updates == 0) return config.polyak;
  return std::pow(config.polyak, static_cast<double>(gradient_steps) /
                                     static_cast<double>(config.polyak_every_updates));
}

DdpgHerConfig original_bc_config(DdpgHerConfig base) {
  base.hidden = {128, 128};
  base.hidden_activation = nn::Activation::kELU;
  base.actor_learning_rate = 1e-4;
  base.batch_size = 1;
  base.updates_per_transition = 1.0;
  return base;
}

}  // namespace pnp::rl
