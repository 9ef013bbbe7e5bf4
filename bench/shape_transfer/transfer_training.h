#pragma once
// The training half of the shape-transfer study (the paper's last step): a hierarchy
// trained on the block, then, per new shape, the roles that adapt (the paper: retract
// only) fine-tuned from the block's checkpoints with the block's experts before them; and
// the end-to-end baseline trained on the block. Everything runs in this process through
// training::train_role, the entry point the training services use.

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rl/training_progress.h"
#include "sim/actuation.h"
#include "sim/object_shape.h"
#include "sim/subtask.h"
#include "sim/world_profile.h"
#include "training/preset.h"
#include "training/role_training.h"

namespace pnp::bench {

// The four roles a hierarchy is served from, in training order.
inline constexpr std::array<const char*, 4> kHierarchyRoles{"approach", "manipulate", "retract",
                                                            "hlc"};

struct HierarchyBlobs {
  std::array<training::Blob, kHierarchyRoles.size()> roles;  // in kHierarchyRoles order
  // The object each role was last trained for (the served grasp follows retract's).
  std::array<sim::ObjectShape, kHierarchyRoles.size()> objects{};
};

// One role's training: what the study reports per role.
struct RoleTraining {
  std::string role;
  rl::TrainingResult result;
};

struct TransferTraining {
  const training::Preset* preset = nullptr;
  sim::WorldProfile world = sim::kDefaultWorldProfile;
  std::uint64_t seed = 0;
  long long fine_tune_max_steps = 60'000;  // per fine-tuned role
  std::size_t threads = 0;
  std::vector<int> hidden;  // the experts' and end-to-end's widths; empty: the preset's
  // The retract gripper prior (DdpgHerConfig::gripper_commitment) while fine-tuning for a
  // new shape only; the block hierarchy and end-to-end train with the preset's.
  double fine_tune_gripper_commitment = 0;
  std::function<void(const std::string& label, const rl::CurvePoint&)> progress;
  sim::Actuation actuation = sim::default_actuation(sim::Robot::kPanda);  // every role's
};

// The block hierarchy on the Panda, trained as the preset says (chained or scripted
// prefixes), each role's result appended to `log`.
HierarchyBlobs train_block_hierarchy(const TransferTraining& t, std::vector<RoleTraining>& log);

// `base` with the roles in `adapted` (any of kHierarchyRoles) fine-tuned for `shape`, in
// training order: each from base's checkpoint of that role, with the (possibly already
// adapted) experts before it. Results appended to `log`.
HierarchyBlobs fine_tune_for_shape(const TransferTraining& t, const HierarchyBlobs& base,
                                   sim::ObjectShape shape, const std::vector<std::string>& adapted,
                                   std::vector<RoleTraining>& log);

// The end-to-end DDPG+HER baseline on the Panda with the block, capped at `max_steps`.
training::Blob train_end_to_end(const TransferTraining& t, long long max_steps,
                                std::vector<RoleTraining>& log);

}  // namespace pnp::bench
