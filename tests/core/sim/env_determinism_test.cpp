// The same seed gives a bit-identical trajectory, whatever the thread count.

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "sim/scripted_evaluation.h"
#include "sim/scripted_expert.h"
#include "sim/subtask_sequence.h"
#include "sim/vec_env.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

// Runs a scripted episode and records every observation, bit for bit.
std::vector<double> trajectory(PickPlaceEnv& env, std::uint64_t seed) {
  std::vector<double> out;
  env.reset(seed);
  SubtaskSequence sequence(layout::kEpisodeSteps);
  while (!env.needs_reset()) {
    const Objective objective = sequence.objective();
    const Action a =
        sequence.idle() ? idle_action() : scripted_action(sequence.current(), env.task_state());
    const StepResult r = env.step(a, env.objective_goal(objective), objective);
    out.insert(out.end(), r.observation.data(), r.observation.data() + kObservationSize);
    out.push_back(r.reward);
    sequence.record_step(r.objective_done);
  }
  return out;
}

bool bit_identical(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(Determinism, SameSeedSameTrajectoryEvenAfterOtherEpisodes) {
  for (Robot robot : kAllRobots) {
    const auto world = testing::world(robot);
    PickPlaceEnv fresh(world), used(world);
    trajectory(used, 999);  // leaves solver warm start and contacts behind
    EXPECT_TRUE(bit_identical(trajectory(fresh, 77), trajectory(used, 77))) << robot_name(robot);
  }
}

TEST(Determinism, DifferentSeedsDiffer) {
  PickPlaceEnv env(testing::world());
  EXPECT_FALSE(bit_identical(trajectory(env, 1), trajectory(env, 2)));
}

TEST(Determinism, VecEnvIsIdenticalAtAnyThreadCount) {
  const auto world = testing::world(Robot::kPanda, ObjectShape::kSmallBlock);
  auto run = [&](std::size_t threads) {
    VecEnv vec(world, 5, threads);
    vec.reset(31);
    std::vector<double> observed;
    std::vector<StepResult> results(vec.size());
    std::vector<Objective> objectives(vec.size(), Objective::kApproach);
    for (int t = 0; t < 60; ++t) {  // crosses an episode boundary: exercises auto-reset
      std::vector<double> actions, goals;
      for (std::size_t i = 0; i < vec.size(); ++i) {
        const Action a = scripted_action(Subtask::kApproach, vec.env(i).task_state());
        const Goal g = vec.env(i).objective_goal(Objective::kApproach);
        actions.insert(actions.end(), a.data(), a.data() + 4);
        goals.insert(goals.end(), g.data(), g.data() + 3);
      }
      vec.step(actions, goals, objectives, results);
      for (const StepResult& r : results) {
        observed.insert(observed.end(), r.observation.data(),
                        r.observation.data() + kObservationSize);
      }
    }
    return observed;
  };
  const auto one = run(1);
  EXPECT_TRUE(bit_identical(one, run(2)));
  EXPECT_TRUE(bit_identical(one, run(4)));
}

TEST(Determinism, ScriptedEvaluationReportDoesNotDependOnThreads) {
  const auto a = evaluate_scripted(Robot::kFetch, ObjectShape::kCylinder, 12, 5, 1);
  const auto b = evaluate_scripted(Robot::kFetch, ObjectShape::kCylinder, 12, 5, 3);
  EXPECT_EQ(a.success_rate, b.success_rate);
  EXPECT_EQ(a.mean_steps, b.mean_steps);
  EXPECT_EQ(a.mean_final_distance_m, b.mean_final_distance_m);
  EXPECT_EQ(a.failed_episodes, b.failed_episodes);
}

}  // namespace
}  // namespace pnp::sim
