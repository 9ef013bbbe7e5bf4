#pragma once
// A subtask expert (or end-to-end policy) on disk: its metadata as JSON, the actor, the
// critic (so fine-tuning can start from it), and the normalisers' statistics, in the
// checksummed container of nn/checkpoint_io.h.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "nn/mlp.h"
#include "nn/normalizer.h"
#include "rl/ddpg_her_agent.h"
#include "sim/gripper_script.h"

namespace pnp::rl {

struct ExpertMeta {
  std::string role;       // approach, manipulate, retract or e2e
  std::string algorithm;  // ddpg_her or bc
  std::string robot, object;
  std::string world = "paper";  // sim/world_profile.h (checkpoints before profiles: paper)
  std::vector<int> hidden;
  nn::Activation hidden_activation = nn::Activation::kReLU;
  bool learn_gripper = true;
  double clip_obs = 200, norm_clip = 5, norm_std_floor = 0.01;
  long long train_env_steps = 0;
  double eval_success = 0;
  std::uint64_t seed = 0;
  std::string code_commit;
  std::string gemm_path{};          // nn/gemm_path.h: which products computed it ("" before kept)
  std::string actuation = "mocap";  // sim/actuation.h (checkpoints before it: mocap)
  // With learn_gripper false, the script that commands the gripper (sim/gripper_script.h;
  // checkpoints before it: the grasp rule, the only one then).
  std::string gripper_script = "grasp_rule";
};

// The gripper script a served or evaluated expert uses: nullopt when it learned its
// gripper. INVALID_ARGUMENT for an unknown script name.
std::optional<sim::GripperScript> scripted_gripper_of(const ExpertMeta& meta);

struct LoadedExpert {
  ExpertMeta meta;
  nn::Mlp actor;
  std::optional<nn::Mlp> critic;
  nn::Normalizer observation_normalizer, goal_normalizer;
};

std::vector<std::uint8_t> save_expert(const ExpertMeta& meta, const nn::Mlp& actor,
                                      const nn::Mlp* critic, const nn::Normalizer& obs_norm,
                                      const nn::Normalizer& goal_norm);
// Throws DATA_LOSS for a corrupted or truncated file, INVALID_ARGUMENT for a file that
// is intact but describes something else (e.g. wrong network widths).
LoadedExpert load_expert(std::span<const std::uint8_t> bytes);

// Restores weights and normaliser statistics into an agent of matching shape (for
// fine-tuning with --init). Throws INVALID_ARGUMENT naming the mismatch.
void restore_agent(DdpgHerAgent& agent, const LoadedExpert& expert);

}  // namespace pnp::rl
