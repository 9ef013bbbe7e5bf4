#include "bench/shape_transfer/transfer_training.h"

#include <algorithm>

#include "build_info.h"

namespace pnp::bench {
namespace {

std::size_t role_index(const std::string& role) {
  const auto* it = std::find(kHierarchyRoles.begin(), kHierarchyRoles.end(), role);
  return static_cast<std::size_t>(it - kHierarchyRoles.begin());
}

// Which learned experts in `blobs` run around a trained expert.
struct Around {
  bool before = false;  // the ones before it, in training and evaluation
  bool after = false;   // the ones after it, in evaluation
};

// One role of the hierarchy trained for `object`, with the experts in `blobs` around it
// as `around` says (experts) or over them (hlc), from `init` (empty: fresh).
training::Blob train_hierarchy_role(const TransferTraining& t, const std::string& role,
                                    sim::ObjectShape object, const HierarchyBlobs& blobs,
                                    Around around, training::Blob init, long long max_steps,
                                    std::vector<RoleTraining>& log) {
  training::TrainingSpec spec = training::preset_spec(*t.preset, role);
  spec.robot = sim::Robot::kPanda;
  spec.object = object;
  spec.world = t.world;
  spec.actuation = t.actuation;
  spec.seed = t.seed;
  if (max_steps > 0) spec.stop.max_steps = max_steps;
  if (!t.hidden.empty()) spec.ddpg.hidden = t.hidden;
  if (!init.empty()) spec.ddpg.gripper_commitment = t.fine_tune_gripper_commitment;
  training::TrainingInputs inputs;
  inputs.init = std::move(init);
  const std::size_t own = role == "hlc" ? sim::kNumSubtasks : role_index(role);
  // The choreographer always sequences the learned experts.
  for (std::size_t k = 0; k < sim::kNumSubtasks; ++k) {
    const bool wanted = role == "hlc" || (k < own ? around.before : k > own && around.after);
    if (wanted) inputs.experts[k] = blobs.roles[k];
  }
  training::TrainingHooks hooks;
  hooks.threads = t.threads;
  const std::string label = role + "/" + std::string(sim::object_name(object));
  hooks.progress = [&](const rl::CurvePoint& p) {
    if (t.progress) t.progress(label, p);
  };
  training::TrainingOutcome out = training::train_role(spec, inputs, hooks, kCodeCommit);
  log.push_back({label, std::move(out.result)});
  return std::move(out.checkpoint);
}

}  // namespace

HierarchyBlobs train_block_hierarchy(const TransferTraining& t, std::vector<RoleTraining>& log) {
  HierarchyBlobs blobs;
  const training::ExpertOrder order = training::expert_order(*t.preset, t.actuation);
  const Around around{order == training::ExpertOrder::kForward,
                      order == training::ExpertOrder::kBackward};
  for (const sim::Subtask subtask : training::training_order(order)) {
    const auto k = static_cast<std::size_t>(subtask);
    blobs.roles[k] = train_hierarchy_role(t, kHierarchyRoles[k], sim::ObjectShape::kBlock, blobs,
                                          around, {}, 0, log);
  }
  const std::size_t hlc = kHierarchyRoles.size() - 1;
  blobs.roles[hlc] = train_hierarchy_role(t, kHierarchyRoles[hlc], sim::ObjectShape::kBlock, blobs,
                                          {}, {}, 0, log);
  return blobs;
}

HierarchyBlobs fine_tune_for_shape(const TransferTraining& t, const HierarchyBlobs& base,
                                   sim::ObjectShape shape, const std::vector<std::string>& adapted,
                                   std::vector<RoleTraining>& log) {
  HierarchyBlobs blobs = base;
  for (std::size_t k = 0; k < kHierarchyRoles.size(); ++k) {
    const std::string role = kHierarchyRoles[k];
    if (std::find(adapted.begin(), adapted.end(), role) == adapted.end()) continue;
    // A fine-tune runs after the hierarchy's learned experts, as the served hierarchy does
    // (the paper's step), unless its preset trains after scripted ones.
    const Around around{t.preset->chained_experts, false};
    blobs.roles[k] = train_hierarchy_role(t, role, shape, blobs, around, base.roles[k],
                                          t.fine_tune_max_steps, log);
    blobs.objects[k] = shape;
  }
  return blobs;
}

training::Blob train_end_to_end(const TransferTraining& t, long long max_steps,
                                std::vector<RoleTraining>& log) {
  training::TrainingSpec spec = training::preset_spec(*t.preset, "e2e");
  spec.robot = sim::Robot::kPanda;
  spec.object = sim::ObjectShape::kBlock;
  spec.world = t.world;
  spec.actuation = t.actuation;
  spec.seed = t.seed;
  spec.stop.max_steps = max_steps;
  if (!t.hidden.empty()) spec.ddpg.hidden = t.hidden;
  training::TrainingHooks hooks;
  hooks.threads = t.threads;
  hooks.progress = [&](const rl::CurvePoint& p) {
    if (t.progress) t.progress("e2e/block", p);
  };
  training::TrainingOutcome out = training::train_role(spec, {}, hooks, kCodeCommit);
  log.push_back({"e2e/block", std::move(out.result)});
  return std::move(out.checkpoint);
}

}  // namespace pnp::bench
