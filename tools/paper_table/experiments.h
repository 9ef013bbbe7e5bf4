#pragma once
// The experiments behind the paper's Table I: train the hierarchy (three subtask experts,
// then the choreographer over them) with DDPG+HER or BC experts, and the end-to-end
// DDPG+HER baseline, each to the same success level; evaluate the final hierarchy on
// held-out episodes.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rl/a3c_trainer.h"
#include "rl/subtask_trainer.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/world_profile.h"

namespace pnp::tools {

struct ExperimentSettings {
  sim::Robot robot = sim::Robot::kFetch;
  sim::ObjectShape object = sim::ObjectShape::kBlock;
  sim::WorldProfile world = sim::kDefaultWorldProfile;
  rl::StopRule expert_stop, hlc_stop, e2e_stop;
  rl::DdpgHerConfig ddpg;  // experts and the end-to-end baseline (BC uses its schedule)
  std::size_t threads = 0;
  int held_out_episodes = 1000;
  // Each expert trained after the learned experts before it (true), or after scripted
  // ones as in the paper (false); see rl::SubtaskTrainingConfig::prefix.
  bool chained = true;
  rl::A3cConfig a3c;  // the choreographer
};

struct RoleRun {
  std::string role;  // approach, manipulate, retract, hlc, e2e
  rl::TrainingResult result;
};

struct MethodRun {
  std::string method;  // ddpg_her, bc, bc_original, e2e
  std::uint64_t seed = 0;
  std::vector<RoleRun> roles;
  bool reached = false;          // every part reached the target
  long long total_steps = 0;     // training steps of all parts (to target, or spent if not reached)
  double total_wall_s = 0;       // training wall time of all parts, evaluation excluded
  double held_out_success = -1;  // hierarchy on held-out episodes (-1: not evaluated)
};

// Each evaluation of one part of one seed's run (the seed: which of the table's runs).
using Progress = std::function<void(const std::string& method, std::uint64_t seed,
                                    const std::string& role, const rl::CurvePoint&)>;

// `method` labels the run (ddpg_her, bc or bc_original); s.ddpg carries its networks.
MethodRun run_hierarchy(const std::string& method, rl::ExpertAlgorithm algorithm,
                        std::uint64_t seed, const ExperimentSettings& s, const Progress& progress);
MethodRun run_end_to_end(std::uint64_t seed, const ExperimentSettings& s, const Progress& progress);

}  // namespace pnp::tools
