#pragma once
// Everything that defines a training run of one role, as a value: which role and
// algorithm, the world, the seed, the stop rule and every hyperparameter. The local tool
// (pnp-train) and the training service both build one; the service stores it as JSON with
// the run, so a run interrupted by a crash is rebuilt from the store exactly.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "rl/a3c_trainer.h"
#include "rl/ddpg_her_config.h"
#include "rl/training_progress.h"
#include "sim/actuation.h"
#include "sim/gripper_script.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_profile.h"

namespace pnp::training {

// The preset (training/preset.h) every tool and the training service start from.
inline constexpr std::string_view kDefaultPreset = "ours";

struct TrainingSpec {
  std::string role = "approach";       // approach, manipulate, retract, hlc or e2e
  std::string algorithm = "ddpg_her";  // ddpg_her, bc, bc_offline (experts), a3c (hlc)
  sim::Robot robot = sim::Robot::kFetch;
  sim::ObjectShape object = sim::ObjectShape::kBlock;
  // The world profile (sim/world_profile.h); runs stored before profiles existed: paper.
  sim::WorldProfile world = sim::kDefaultWorldProfile;
  // How the hand follows actions (sim/actuation.h); runs stored before it existed: mocap.
  sim::Actuation actuation = sim::Actuation::kMocap;
  std::uint64_t seed = 0;
  // The preset the spec started from, before any single value was overridden ("": a run
  // stored before presets existed).
  std::string preset;
  rl::StopRule stop;
  rl::DdpgHerConfig ddpg;
  bool scripted_gripper = false;  // experts: keep the gripper command scripted (the paper's)
  // ... by this script (sim/gripper_script.h); specs stored before it: the grasp rule.
  sim::GripperScript gripper_script = sim::GripperScript::kGraspRule;
  rl::A3cConfig a3c;

  bool is_expert() const;  // approach, manipulate or retract
  // Throws INVALID_ARGUMENT naming the field: unknown role or algorithm, an algorithm the
  // role cannot use, an actuation the robot does not have, and every hyperparameter out
  // of range.
  void validate() const;
};

// The learner's configuration as it trains: for experts learn_gripper follows
// scripted_gripper, and the end-to-end baseline explores with random gripper actions.
rl::DdpgHerConfig effective_ddpg(const TrainingSpec& spec);

nlohmann::json to_json(const TrainingSpec& spec);
// The inverse of to_json; missing fields keep their defaults. Throws INVALID_ARGUMENT.
TrainingSpec spec_from_json(const nlohmann::json& json);

}  // namespace pnp::training
