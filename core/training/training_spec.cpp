#include "training/training_spec.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/error.h"

namespace pnp::training {
namespace {

constexpr std::array<std::string_view, 3> kExpertRoles{"approach", "manipulate", "retract"};

}  // namespace

bool TrainingSpec::is_expert() const {
  return std::find(kExpertRoles.begin(), kExpertRoles.end(), role) != kExpertRoles.end();
}

void TrainingSpec::validate() const {
  if (is_expert()) {
    if (algorithm != "ddpg_her" && algorithm != "bc" && algorithm != "bc_offline") {
      throw_invalid_argument("algorithm", "one of ddpg_her, bc, bc_offline for a subtask expert",
                             "\"" + algorithm + "\"");
    }
  } else if (role == "e2e") {
    if (algorithm != "ddpg_her") {
      throw_invalid_argument("algorithm", "ddpg_her for the end-to-end baseline",
                             "\"" + algorithm + "\"");
    }
  } else if (role == "hlc") {
    if (algorithm != "a3c")
      throw_invalid_argument("algorithm", "a3c for the choreographer", "\"" + algorithm + "\"");
  } else {
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + role + "\"");
  }
  sim::require_supported(robot, actuation);
  stop.validate();
  if (role == "hlc") {
    a3c.validate();
  } else {
    effective_ddpg(*this).validate();
  }
}

rl::DdpgHerConfig effective_ddpg(const TrainingSpec& spec) {
  rl::DdpgHerConfig config = spec.ddpg;
  const bool end_to_end = spec.role == "e2e";
  config.learn_gripper = !spec.scripted_gripper || end_to_end;
  config.gripper_script = spec.gripper_script;
  if (end_to_end) config.random_gripper = true;  // the standard end-to-end setup
  return config;
}

nlohmann::json to_json(const TrainingSpec& s) {
  const rl::DdpgHerConfig& d = s.ddpg;
  return {{"role", s.role},
          {"algorithm", s.algorithm},
          {"robot", sim::robot_name(s.robot)},
          {"object", sim::object_name(s.object)},
          {"world", sim::world_profile_name(s.world)},
          {"actuation", sim::actuation_name(s.actuation)},
          {"seed", s.seed},
          {"preset", s.preset},
          {"stop",
           {{"max_steps", s.stop.max_steps},
            {"target_success", s.stop.target_success},
            {"eval_interval_steps", s.stop.eval_interval_steps},
            {"eval_episodes", s.stop.eval_episodes},
            {"consecutive", s.stop.consecutive},
            {"fresh_eval_scenes", s.stop.fresh_eval_scenes}}},
          {"scripted_gripper", s.scripted_gripper},
          {"gripper_script", sim::gripper_script_name(s.gripper_script)},
          {"ddpg",
           {{"hidden", d.hidden},
            {"hidden_activation", std::string(nn::activation_name(d.hidden_activation))},
            {"actor_learning_rate", d.actor_learning_rate},
            {"critic_learning_rate", d.critic_learning_rate},
            {"gamma", d.gamma},
            {"polyak", d.polyak},
            {"batch_size", d.batch_size},
            {"buffer_size", d.buffer_size},
            {"her_k", d.her_k},
            {"noise_eps", d.noise_eps},
            {"random_eps", d.random_eps},
            {"random_gripper", d.random_gripper},
            {"action_l2", d.action_l2},
            {"gripper_commitment", d.gripper_commitment},
            {"clip_obs", d.clip_obs},
            {"norm_clip", d.norm_clip},
            {"norm_std_floor", d.norm_std_floor},
            {"episodes_per_cycle", d.episodes_per_cycle},
            {"updates_per_cycle", d.updates_per_cycle},
            {"updates_per_transition", d.updates_per_transition},
            {"polyak_every_updates", d.polyak_every_updates},
            {"demo_episodes", d.demo_episodes},
            {"demo_pretrain_updates", d.demo_pretrain_updates},
            {"demo_bc_weight", d.demo_bc_weight},
            {"demo_batch_size", d.demo_batch_size}}},
          {"a3c",
           {{"workers", s.a3c.workers},
            {"learning_rate", s.a3c.learning_rate},
            {"gamma", s.a3c.gamma},
            {"gae_lambda", s.a3c.gae_lambda},
            {"entropy_weight", s.a3c.entropy_weight},
            {"exploring_starts", s.a3c.exploring_starts},
            {"value_weight", s.a3c.value_weight},
            {"max_grad_norm", s.a3c.max_grad_norm},
            {"trunk", s.a3c.network.trunk},
            {"lstm", s.a3c.network.lstm},
            {"predicate_inputs", s.a3c.network.predicate_inputs},
            {"mask_finished", s.a3c.network.mask_finished},
            {"chain_prior", s.a3c.network.chain_prior}}}};
}

namespace {

template <typename T>
struct IsVector : std::false_type {};
template <typename T>
struct IsVector<std::vector<T>> : std::true_type {};

// `value` as a T, refused (naming `field`) unless it is one exactly: an integer field takes
// only integers within its range (JSON's 3.5 or 1e70 would otherwise be cast, undefined
// behaviour for the latter), a flag only true or false.
template <typename T>
T checked(const nlohmann::json& value, const std::string& field) {
  const auto refuse = [&](const char* expected) -> T {
    throw_invalid_argument(field, expected, value.dump());
  };
  if constexpr (std::is_same_v<T, bool>) {
    return value.is_boolean() ? value.get<bool>() : refuse("true or false");
  } else if constexpr (std::is_integral_v<T>) {
    if (value.is_number_unsigned() && std::in_range<T>(value.get<std::uint64_t>()))
      return static_cast<T>(value.get<std::uint64_t>());
    if (value.is_number_integer() && std::in_range<T>(value.get<std::int64_t>()))
      return static_cast<T>(value.get<std::int64_t>());
    return refuse(std::is_signed_v<T> ? "an integer in range" : "a non-negative integer in range");
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!value.is_number()) return refuse("a number");
    const double number = value.get<double>();
    if (std::isfinite(number) && std::abs(number) > std::numeric_limits<T>::max())
      return refuse("a number in range");
    return static_cast<T>(number);
  } else if constexpr (IsVector<T>::value) {
    if (!value.is_array()) return refuse("a list");
    T out;
    for (std::size_t i = 0; i < value.size(); ++i)
      out.push_back(
          checked<typename T::value_type>(value[i], field + "[" + std::to_string(i) + "]"));
    return out;
  } else {
    if (!value.is_string()) return refuse("a string");
    return value.get<T>();
  }
}

template <typename T>
void read(const nlohmann::json& object, const char* key, T& out, const std::string& path) {
  if (!object.contains(key)) return;
  out = checked<T>(object.at(key), path + key);
}

}  // namespace

TrainingSpec spec_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw_invalid_argument("config", "a JSON object", j.dump());
  TrainingSpec s;
  read(j, "role", s.role, "");
  read(j, "algorithm", s.algorithm, "");
  std::string robot(sim::robot_name(s.robot)), object(sim::object_name(s.object));
  read(j, "robot", robot, "");
  read(j, "object", object, "");
  s.robot = sim::parse_robot(robot, "robot");
  s.object = sim::parse_object(object, "object");
  // A spec without a world was stored before world profiles: it trained in the paper world.
  std::string world(sim::world_profile_name(sim::WorldProfile::kPaper));
  read(j, "world", world, "");
  s.world = sim::parse_world_profile(world, "world");
  // A spec without an actuation was stored before it existed: the hand was on the mocap.
  std::string actuation(sim::actuation_name(sim::Actuation::kMocap));
  read(j, "actuation", actuation, "");
  s.actuation = sim::parse_actuation(actuation, "actuation");
  read(j, "seed", s.seed, "");
  read(j, "preset", s.preset, "");
  read(j, "scripted_gripper", s.scripted_gripper, "");
  std::string gripper_script(sim::gripper_script_name(s.gripper_script));
  read(j, "gripper_script", gripper_script, "");
  s.gripper_script = sim::parse_gripper_script(gripper_script, "gripper_script");
  if (const auto stop = j.find("stop"); stop != j.end()) {
    read(*stop, "max_steps", s.stop.max_steps, "stop.");
    read(*stop, "target_success", s.stop.target_success, "stop.");
    read(*stop, "eval_interval_steps", s.stop.eval_interval_steps, "stop.");
    read(*stop, "eval_episodes", s.stop.eval_episodes, "stop.");
    read(*stop, "consecutive", s.stop.consecutive, "stop.");
    read(*stop, "fresh_eval_scenes", s.stop.fresh_eval_scenes, "stop.");
  }
  if (const auto ddpg = j.find("ddpg"); ddpg != j.end()) {
    rl::DdpgHerConfig& d = s.ddpg;
    const std::string p = "ddpg.";
    read(*ddpg, "hidden", d.hidden, p);
    std::string activation(nn::activation_name(d.hidden_activation));
    read(*ddpg, "hidden_activation", activation, p);
    d.hidden_activation = nn::parse_activation(activation, p + "hidden_activation");
    read(*ddpg, "actor_learning_rate", d.actor_learning_rate, p);
    read(*ddpg, "critic_learning_rate", d.critic_learning_rate, p);
    read(*ddpg, "gamma", d.gamma, p);
    read(*ddpg, "polyak", d.polyak, p);
    read(*ddpg, "batch_size", d.batch_size, p);
    read(*ddpg, "buffer_size", d.buffer_size, p);
    read(*ddpg, "her_k", d.her_k, p);
    read(*ddpg, "noise_eps", d.noise_eps, p);
    read(*ddpg, "random_eps", d.random_eps, p);
    read(*ddpg, "random_gripper", d.random_gripper, p);
    read(*ddpg, "action_l2", d.action_l2, p);
    read(*ddpg, "gripper_commitment", d.gripper_commitment, p);
    read(*ddpg, "clip_obs", d.clip_obs, p);
    read(*ddpg, "norm_clip", d.norm_clip, p);
    read(*ddpg, "norm_std_floor", d.norm_std_floor, p);
    read(*ddpg, "episodes_per_cycle", d.episodes_per_cycle, p);
    read(*ddpg, "updates_per_cycle", d.updates_per_cycle, p);
    read(*ddpg, "updates_per_transition", d.updates_per_transition, p);
    read(*ddpg, "polyak_every_updates", d.polyak_every_updates, p);
    read(*ddpg, "demo_episodes", d.demo_episodes, p);
    read(*ddpg, "demo_pretrain_updates", d.demo_pretrain_updates, p);
    read(*ddpg, "demo_bc_weight", d.demo_bc_weight, p);
    read(*ddpg, "demo_batch_size", d.demo_batch_size, p);
  }
  if (const auto a3c = j.find("a3c"); a3c != j.end()) {
    const std::string p = "a3c.";
    read(*a3c, "workers", s.a3c.workers, p);
    read(*a3c, "learning_rate", s.a3c.learning_rate, p);
    read(*a3c, "gamma", s.a3c.gamma, p);
    read(*a3c, "gae_lambda", s.a3c.gae_lambda, p);
    read(*a3c, "entropy_weight", s.a3c.entropy_weight, p);
    read(*a3c, "exploring_starts", s.a3c.exploring_starts, p);
    read(*a3c, "value_weight", s.a3c.value_weight, p);
    read(*a3c, "max_grad_norm", s.a3c.max_grad_norm, p);
    read(*a3c, "trunk", s.a3c.network.trunk, p);
    read(*a3c, "lstm", s.a3c.network.lstm, p);
    read(*a3c, "predicate_inputs", s.a3c.network.predicate_inputs, p);
    read(*a3c, "mask_finished", s.a3c.network.mask_finished, p);
    read(*a3c, "chain_prior", s.a3c.network.chain_prior, p);
  }
  return s;
}

}  // namespace pnp::training
