#pragma once
// Trains one role from a TrainingSpec and checkpoint bytes, and returns its result and
// final checkpoint: the one entry point shared by the local tool (files) and the training
// service (the store). It knows nothing of where checkpoints live.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rl/training_progress.h"
#include "sim/env_factory.h"
#include "sim/subtask.h"
#include "training/training_spec.h"

namespace pnp::training {

using Blob = std::vector<std::uint8_t>;

// Checkpoints a run starts from. An empty blob is the scripted expert.
struct TrainingInputs {
  Blob init;  // fine-tune (or resume) from this checkpoint of the same role; empty: fresh
  // Experts: who runs the subtasks before this one, and in evaluation after it (the role's
  // own entry is unused; empty entries are scripted). The choreographer: the three experts
  // it sequences.
  std::array<Blob, sim::kNumSubtasks> experts;
};

// Makes the environment factory for a world: where rollouts and evaluations run (remote
// simulation services, say). Results do not depend on it.
using EnvironmentSource = std::function<std::unique_ptr<sim::EnvFactory>(
    sim::Robot, sim::ObjectShape, sim::WorldProfile, sim::Actuation)>;

struct TrainingHooks {
  std::size_t threads = 0;  // rollout and evaluation threads (0: all cores); no effect on results
  EnvironmentSource environments;  // empty: in this process
  rl::TrainingControl control;
  // After every evaluation: the point and the checkpoint of the weights it evaluated.
  std::function<void(const rl::CurvePoint&, const Blob&)> on_evaluation;
  rl::ProgressCallback progress;
};

struct TrainingOutcome {
  rl::TrainingResult result;
  Blob checkpoint;  // the final weights
};

// Throws INVALID_ARGUMENT for an invalid spec or a checkpoint of the wrong role or shape,
// DATA_LOSS for a corrupted one.
TrainingOutcome train_role(const TrainingSpec& spec, const TrainingInputs& inputs,
                           const TrainingHooks& hooks, const std::string& code_commit);

}  // namespace pnp::training
