#include "services/train/train_convert.h"

#include <charconv>

#include "common/error.h"
#include "services/common/convert.h"
#include "training/preset.h"

namespace pnp::services {
namespace {

[[noreturn]] void bad_enum(std::string_view field, std::string_view expected, int value) {
  throw_invalid_argument(field, expected, std::to_string(value));
}

void read_stop(const train::v1::StopRule& in, rl::StopRule& out) {
  if (in.has_max_steps()) out.max_steps = in.max_steps();
  if (in.has_target_success()) out.target_success = in.target_success();
  if (in.has_eval_interval_steps()) out.eval_interval_steps = in.eval_interval_steps();
  if (in.has_eval_episodes()) out.eval_episodes = in.eval_episodes();
  if (in.has_fresh_eval_scenes()) out.fresh_eval_scenes = in.fresh_eval_scenes();
}

void read_ddpg(const train::v1::DdpgHerConfig& in, training::TrainingSpec& spec) {
  rl::DdpgHerConfig& out = spec.ddpg;
  if (in.hidden_size() > 0) out.hidden.assign(in.hidden().begin(), in.hidden().end());
  if (in.has_actor_learning_rate()) out.actor_learning_rate = in.actor_learning_rate();
  if (in.has_critic_learning_rate()) out.critic_learning_rate = in.critic_learning_rate();
  if (in.has_gamma()) out.gamma = in.gamma();
  if (in.has_polyak()) out.polyak = in.polyak();
  if (in.has_batch_size()) out.batch_size = in.batch_size();
  if (in.has_buffer_size()) out.buffer_size = in.buffer_size();
  if (in.has_her_k()) out.her_k = in.her_k();
  if (in.has_noise_eps()) out.noise_eps = in.noise_eps();
  if (in.has_random_eps()) out.random_eps = in.random_eps();
  if (in.has_action_l2()) out.action_l2 = in.action_l2();
  if (in.has_gripper_commitment()) out.gripper_commitment = in.gripper_commitment();
  if (in.has_updates_per_cycle()) out.updates_per_cycle = in.updates_per_cycle();
  if (in.has_updates_per_transition()) out.updates_per_transition = in.updates_per_transition();
  if (in.has_scripted_gripper()) spec.scripted_gripper = in.scripted_gripper();
  if (in.has_demo_episodes()) out.demo_episodes = in.demo_episodes();
  if (in.has_polyak_every_updates()) out.polyak_every_updates = in.polyak_every_updates();
  if (in.has_demo_pretrain_updates()) out.demo_pretrain_updates = in.demo_pretrain_updates();
  if (in.has_demo_bc_weight()) out.demo_bc_weight = in.demo_bc_weight();
}

void read_a3c(const train::v1::A3cConfig& in, rl::A3cConfig& out) {
  if (in.has_workers()) out.workers = in.workers();
  if (in.has_learning_rate()) out.learning_rate = in.learning_rate();
  if (in.has_gamma()) out.gamma = in.gamma();
  if (in.has_entropy_weight()) out.entropy_weight = in.entropy_weight();
  if (in.has_exploring_starts()) out.exploring_starts = in.exploring_starts();
  if (in.has_chain_prior()) out.network.chain_prior = in.chain_prior();
  if (in.has_predicate_inputs()) out.network.predicate_inputs = in.predicate_inputs();
  if (in.has_mask_finished()) out.network.mask_finished = in.mask_finished();
}

}  // namespace

std::string algorithm_name(train::v1::Algorithm algorithm, std::string_view field) {
  switch (algorithm) {
    case train::v1::ALGORITHM_DDPG_HER:
      return "ddpg_her";
    case train::v1::ALGORITHM_BC:
      return "bc";
    case train::v1::ALGORITHM_BC_OFFLINE:
      return "bc_offline";
    case train::v1::ALGORITHM_A3C:
      return "a3c";
    default:
      bad_enum(field,
               "one of ALGORITHM_DDPG_HER, ALGORITHM_BC, ALGORITHM_BC_OFFLINE, ALGORITHM_A3C",
               algorithm);
  }
}

train::v1::Algorithm algorithm_from_name(std::string_view name) {
  if (name == "ddpg_her") return train::v1::ALGORITHM_DDPG_HER;
  if (name == "bc") return train::v1::ALGORITHM_BC;
  if (name == "bc_offline") return train::v1::ALGORITHM_BC_OFFLINE;
  if (name == "a3c") return train::v1::ALGORITHM_A3C;
  return train::v1::ALGORITHM_UNSPECIFIED;
}

std::pair<training::TrainingSpec, training::CheckpointRefs> from_proto(
    const train::v1::CreateTrainingRunRequest& r) {
  const training::Preset& preset = training::find_preset(
      r.preset().empty() ? training::kDefaultPreset : std::string_view(r.preset()), "preset");
  training::TrainingSpec spec = training::preset_spec(preset, role_name(r.role(), "role"));
  spec.algorithm = algorithm_name(r.algorithm(), "algorithm");
  spec.robot = from_proto(r.robot(), "robot");
  spec.object = from_proto(r.object(), "object");
  spec.world = from_proto(r.world(), "world");
  spec.actuation = from_proto(r.actuation(), spec.robot, "actuation");
  spec.seed = r.seed();
  read_stop(r.stop(), spec.stop);
  read_ddpg(r.ddpg(), spec);
  read_a3c(r.a3c(), spec.a3c);
  training::CheckpointRefs refs;
  if (r.parent_checkpoint_id() < 0) {
    throw_invalid_argument("parent_checkpoint_id", "a checkpoint id, or 0 for none",
                           std::to_string(r.parent_checkpoint_id()));
  }
  if (r.parent_checkpoint_id() > 0) refs.parent = r.parent_checkpoint_id();
  if (spec.role == "hlc") {
    if (r.prefix_checkpoint_ids_size() > 0)
      throw_invalid_argument("prefix_checkpoint_ids", "none for the choreographer",
                             std::to_string(r.prefix_checkpoint_ids_size()) + " ids");
    if (r.successor_checkpoint_ids_size() > 0)
      throw_invalid_argument("successor_checkpoint_ids", "none for the choreographer",
                             std::to_string(r.successor_checkpoint_ids_size()) + " ids");
    refs.experts.assign(r.expert_checkpoint_ids().begin(), r.expert_checkpoint_ids().end());
  } else {
    if (r.expert_checkpoint_ids_size() > 0)
      throw_invalid_argument("expert_checkpoint_ids", "none (only the choreographer takes them)",
                             std::to_string(r.expert_checkpoint_ids_size()) + " ids");
    refs.experts.assign(r.prefix_checkpoint_ids().begin(), r.prefix_checkpoint_ids().end());
    refs.successors.assign(r.successor_checkpoint_ids().begin(),
                           r.successor_checkpoint_ids().end());
  }
  return {spec, refs};
}

train::v1::RunState to_proto(store::RunState state) {
  switch (state) {
    case store::RunState::kPending:
      return train::v1::RUN_STATE_PENDING;
    case store::RunState::kRunning:
      return train::v1::RUN_STATE_RUNNING;
    case store::RunState::kSucceeded:
      return train::v1::RUN_STATE_SUCCEEDED;
    case store::RunState::kFailed:
      return train::v1::RUN_STATE_FAILED;
    case store::RunState::kCancelled:
      return train::v1::RUN_STATE_CANCELLED;
  }
  return train::v1::RUN_STATE_UNSPECIFIED;
}

store::RunState from_proto(train::v1::RunState state, std::string_view field) {
  switch (state) {
    case train::v1::RUN_STATE_PENDING:
      return store::RunState::kPending;
    case train::v1::RUN_STATE_RUNNING:
      return store::RunState::kRunning;
    case train::v1::RUN_STATE_SUCCEEDED:
      return store::RunState::kSucceeded;
    case train::v1::RUN_STATE_FAILED:
      return store::RunState::kFailed;
    case train::v1::RUN_STATE_CANCELLED:
      return store::RunState::kCancelled;
    default:
      bad_enum(field, "a RUN_STATE_ value", state);
  }
}

void to_proto(const store::MetricPoint& p, train::v1::MetricPoint& out) {
  out.set_env_steps(p.env_steps);
  out.set_episodes(p.episodes);
  out.set_wall_s(p.wall_s);
  out.set_task_success(p.task_success);
  out.set_subtask_success(p.subtask_success);
  out.set_sampled_success(p.sampled_success);
  out.set_critic_loss(p.critic_loss);
  out.set_actor_loss(p.actor_loss);
  out.set_updates(p.updates);
  if (p.stop_score) out.set_stop_score(*p.stop_score);
}

void set_millis(store::Millis ms, google::protobuf::Timestamp& out) {
  out.set_seconds(ms / 1000);
  out.set_nanos(static_cast<int>((ms % 1000) * 1'000'000));
}

void to_proto(const store::CheckpointInfo& c, train::v1::Checkpoint& out) {
  out.set_checkpoint_id(c.id);
  out.set_run_id(c.run_id);
  out.set_role(role_from_name(c.role));
  out.set_env_steps(c.env_steps);
  out.set_eval_success(c.eval_success);
  out.set_evaluated(!c.unevaluated.has_value());
  out.set_checksum(c.checksum);
  out.set_size_bytes(c.size_bytes);
  set_millis(c.created_ms, *out.mutable_create_time());
}

std::string page_token_after(std::int64_t last_run_id) {
  return std::to_string(last_run_id);
}

std::int64_t run_id_from_page_token(const std::string& token) {
  if (token.empty()) return 0;
  std::int64_t id = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), id);
  if (error != std::errc() || end != token.data() + token.size() || id <= 0)
    throw_invalid_argument("page_token", "a token from a previous response", "\"" + token + "\"");
  return id;
}

}  // namespace pnp::services
