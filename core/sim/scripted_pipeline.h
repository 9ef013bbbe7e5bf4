#pragma once
// Runs one episode with a fixed sequence of subtask experts: approach, manipulate,
// retract, each until its termination predicate or its step cap, then idle with the
// gripper closed until step 50. Success is read at the last step, from the object.
// Each subtask's expert is any SubtaskPolicy: all scripted, or one learned expert with
// scripted others (how a subtask expert is evaluated).

#include <array>
#include <cstdint>
#include <functional>
#include <optional>

#include "sim/environment.h"
#include "sim/subtask.h"
#include "sim/subtask_policy.h"

namespace pnp::sim {

struct EpisodeOutcome {
  bool success = false;  // object within 0.05 m of the goal after step 50
  int active_steps = 0;  // steps until retract ended (50 if it never did)
  int env_steps = 0;     // every step taken, idle ones included
  std::array<int, kNumSubtasks> subtask_steps{};
  std::array<bool, kNumSubtasks> subtask_done{};  // ended by its predicate, not its cap
  double final_distance_m = 0;                    // object to goal at the end
  PhysicsFault fault = PhysicsFault::kNone;       // what ended the episode early, if anything
  bool physics_fault() const { return fault != PhysicsFault::kNone; }
};

using SubtaskPolicies = std::array<SubtaskPolicy*, kNumSubtasks>;

// Sees every step after it is taken: the subtask that acted (none when idle), the action
// and the state it led to. For tracing an episode; never changes it.
using PipelineStepObserver = std::function<void(int step, std::optional<Subtask> acting,
                                                const Action& action, const TaskState& after)>;

EpisodeOutcome run_pipeline_episode(Environment& env, const SubtaskPolicies& policies,
                                    std::uint64_t seed, const PipelineStepObserver& observer = {});

// All three experts scripted.
EpisodeOutcome run_scripted_episode(Environment& env, std::uint64_t seed);

}  // namespace pnp::sim
