#pragma once
// Named training configurations, so that nobody assembles the headline from flags. A
// preset fixes everything that differs between the paper's method as published and ours:
// demonstrations, the gripper, the update schedule, the target rate, chained experts, the
// stop rules and what the choreographer sees. Every tool and the training service start
// from one (kDefaultPreset unless told otherwise); explicit flags or request fields then
// override single values.
//
//   paper       the paper as published: no demonstrations, the gripper a constant per
//               subtask as its code commands it (approach open, then closed), experts
//               after scripted prefixes, the original's 40 updates per 2-episode cycle,
//               a choreographer that sees observation and goal only (no predicate inputs,
//               no masking), evaluation once per epoch (5k steps).
//   ours        every improvement of ours that uses no demonstrations: the gripper scripted
//               by the grasp rule (closed once centred on the object: domain knowledge),
//               chained experts, 0.5 updates per transition at the original's target
//               rate per gradient step, experts and choreographer stopped at 97%, predicate inputs
//               and masking for the choreographer (domain knowledge computed from observation and
//               goal), a prior toward the experts' order (chain_prior 2), evaluation every 1k
//               steps.
//   ours+demos  ours plus 10 scripted demonstration episodes per expert (their steps
//               counted), 300 cloning updates and a behaviour-cloning term of weight 5.

#include <array>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>

#include "rl/a3c_trainer.h"
#include "rl/ddpg_her_config.h"
#include "rl/training_progress.h"
#include "sim/actuation.h"
#include "sim/gripper_script.h"
#include "sim/subtask.h"
#include "training/training_spec.h"

namespace pnp::training {

struct Preset {
  std::string_view name;
  std::string_view summary;
  bool uses_demonstrations = false;
  // Each expert trains after the learned experts before it (true) or after scripted ones.
  bool chained_experts = true;
  bool scripted_gripper = false;
  sim::GripperScript gripper_script = sim::GripperScript::kGraspRule;  // when scripted
  rl::DdpgHerConfig ddpg;  // experts and the end-to-end baseline
  rl::A3cConfig a3c;       // the choreographer
  rl::StopRule expert_stop, hlc_stop, e2e_stop;
};

// The order a preset's experts train in, and who runs the other subtasks meanwhile.
enum class ExpertOrder {
  kScriptedOthers,  // any order, each after and before the scripted experts (the paper)
  kForward,         // approach, manipulate, retract: each after the learned experts before it
  kBackward,        // retract, manipulate, approach: each judged with the learned ones after it
};
std::string_view expert_order_name(ExpertOrder order);  // "scripted", "forward", "backward"
// The subtasks in training order.
std::array<sim::Subtask, sim::kNumSubtasks> training_order(ExpertOrder order);

// How `preset` chains its experts in a world with `actuation`: forward, except that on
// the arm-actuated world they chain backward, since there the scripted experts after an
// expert run out of the 50 steps on a tenth of the scenes, and the stop rule could not
// tell a good expert from a bad one (docs/LEARNING.md, "Backward chaining").
ExpertOrder expert_order(const Preset& preset, sim::Actuation actuation);

// Every preset, in the order above.
std::span<const Preset> presets();
// Throws INVALID_ARGUMENT naming `field` and the preset names.
const Preset& find_preset(std::string_view name, std::string_view field);

// The training spec of one role (approach, manipulate, retract, hlc or e2e) under the
// preset, with the role's default algorithm (ddpg_her, or a3c for hlc).
TrainingSpec preset_spec(const Preset& preset, std::string_view role);

// The whole preset: every role's spec and the settings outside them.
nlohmann::json to_json(const Preset& preset);

}  // namespace pnp::training
