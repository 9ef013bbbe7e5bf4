#pragma once
// Trains one subtask expert with DDPG+HER: cycles of parallel exploratory episodes (after
// the prefix), stored as segments, followed by gradient updates; at every evaluation
// interval the expert is evaluated on fresh seeded episodes after the same prefix and
// with scripted experts after it (never counted as training steps), until the target is
// reached twice in a row or the step cap.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "common/thread_pool.h"
#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "rl/training_progress.h"
#include "sim/env_factory.h"
#include "sim/subtask_policy.h"

namespace pnp::rl {

enum class ExpertAlgorithm {
  kDdpgHer,    // DDPG + HER (with demonstrations, see DdpgHerConfig)
  kBcOnline,   // behaviour cloning, DAgger-style: the learner acts (with noise), every
               // visited state is labelled with the scripted expert's action
  kBcOffline,  // behaviour cloning on scripted demonstrations only
  kEndToEnd,   // one DDPG+HER policy for the whole task, sparse reward, no demonstrations
};

struct SubtaskTrainingConfig {
  ExpertAlgorithm algorithm = ExpertAlgorithm::kDdpgHer;
  sim::Subtask subtask = sim::Subtask::kApproach;
  std::uint64_t seed = 0;
  DdpgHerConfig ddpg;
  StopRule stop;
  std::size_t threads = 0;
  const LoadedExpert* init = nullptr;  // fine-tune from this checkpoint
  // Who runs the subtasks before this one, in training and in evaluation; null entries
  // (the default) are the scripted experts, as in the paper. Passing the learned experts
  // already trained ("chained" training) trains each expert on the states it will start
  // from when the hierarchy runs (docs/LEARNING.md). Entries from `subtask` on are unused.
  std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks> prefix{};
  // Who runs the subtasks after this one in evaluation (training episodes end with the
  // subtask); null entries, the default, are the scripted experts. Learned successors
  // judge an expert by the task the hierarchy will do, where the scripted experts cannot
  // finish it in time (on the arm-actuated world: docs/LEARNING.md, "Backward chaining").
  // Entries up to `subtask` are unused.
  std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks> successors{};
  TrainingControl control;
  // Called after every evaluation with the agent as evaluated (to checkpoint it), before
  // the progress callback.
  std::function<void(const CurvePoint&, const DdpgHerAgent&)> on_evaluation;
};

// What the stop rule scores for an expert: approach and manipulate must also do their own
// subtask (see subtask_trainer.cpp); retract and end-to-end are judged on the task.
// The agent's configuration for this expert: the gripper prior (gripper_commitment) is
// the retract expert's only, since retract alone must keep one end (closed) all along.
DdpgHerConfig agent_config(const SubtaskTrainingConfig& config);

double expert_stop_score(const CurvePoint& point, sim::Subtask subtask, bool end_to_end);

struct SubtaskTrainingOutput {
  TrainingResult result;
  std::unique_ptr<DdpgHerAgent> agent;
};

SubtaskTrainingOutput train_subtask_expert(const sim::EnvFactory& envs,
                                           const SubtaskTrainingConfig& config,
                                           const ProgressCallback& progress = {});

}  // namespace pnp::rl
