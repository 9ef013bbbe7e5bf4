#pragma once
// Evaluates the pipeline (scripted, or with learned experts) over many seeded episodes. Episode i
// always uses derive_seed(seed, i), and results are gathered by episode index, so the report is
// identical at any thread count.

#include <cstdint>
#include <memory>
#include <vector>

#include "common/thread_pool.h"
#include "sim/env_factory.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "sim/scripted_pipeline.h"

namespace pnp::sim {

struct ScriptedEvalReport {
  Robot robot = Robot::kFetch;
  ObjectShape object = ObjectShape::kBlock;
  WorldProfile world = WorldProfile::kPaper;
  Actuation actuation = Actuation::kMocap;
  std::uint64_t seed = 0;
  int episodes = 0;
  double success_rate = 0;
  double success_ci95_low = 0;  // Wilson score interval
  double success_ci95_high = 0;
  double mean_steps = 0;  // steps until retract ended (the pipeline's active steps)
  double std_steps = 0;
  long long env_steps = 0;  // every environment step taken, idle ones included
  std::array<double, kNumSubtasks> subtask_success_rate{};  // ended by its predicate
  std::array<double, kNumSubtasks> subtask_mean_steps{};
  double mean_final_distance_m = 0;
  int physics_faults = 0;
  std::vector<int> failed_episodes;  // indices, for reproduction with --seed
  // Where the failed episodes went wrong: the first subtask that never met its predicate,
  // or (failed_after_all_done) every predicate met but the object not at the goal at the end.
  std::array<int, kNumSubtasks> failed_in_subtask{};
  int failed_after_all_done = 0;
};

// episodes and threads must be positive (threads == 0: one per hardware thread).
ScriptedEvalReport evaluate_scripted(Robot robot, ObjectShape object, long long episodes,
                                     std::uint64_t seed, std::size_t threads = 0,
                                     WorldProfile world = WorldProfile::kPaper);

// The same evaluation with any experts: each worker runs its own clone of each
// prototype. Episode i uses derive_seed(seed, i).
ScriptedEvalReport evaluate_pipeline(const EnvFactory& envs,
                                     const std::array<const SubtaskPolicy*, kNumSubtasks>& experts,
                                     long long episodes, std::uint64_t seed, ThreadPool& pool);

}  // namespace pnp::sim
