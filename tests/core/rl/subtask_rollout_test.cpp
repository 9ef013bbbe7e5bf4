#include "rl/subtask_rollout.h"

#include <gtest/gtest.h>

#include "rl/hlc_episode.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_expert.h"

namespace pnp::rl {
namespace {

// The scripted expert, counting the calls per subtask it is asked to run.
class CountingPolicy final : public sim::SubtaskPolicy {
 public:
  sim::Action act(sim::Subtask subtask, const sim::Observation& observation, const sim::Goal& goal,
                  const sim::TaskState& state) override {
    ++calls[static_cast<std::size_t>(subtask)];
    return scripted_.act(subtask, observation, goal, state);
  }
  std::unique_ptr<sim::SubtaskPolicy> clone() const override {
    return std::make_unique<CountingPolicy>();
  }
  std::array<int, sim::kNumSubtasks> calls{};

 private:
  sim::ScriptedPolicy scripted_;
};

std::shared_ptr<const sim::WorldModel> fetch_block() {
  return sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock);
}

TEST(SubtaskRollout, ThePrefixPoliciesRunTheEarlierSubtasksAndAreCounted) {
  sim::PickPlaceEnv env(fetch_block());
  CountingPolicy approach, manipulate, expert;
  sim::ScriptedPolicy unused;
  Rng rng(0);
  const SubtaskEpisode e =
      run_subtask_episode(env, sim::Subtask::kRetract, {&approach, &manipulate, &unused}, expert,
                          nullptr, derive_seed(4, 0), rng);
  EXPECT_GT(approach.calls[0], 0);
  EXPECT_EQ(approach.calls[1] + approach.calls[2], 0) << "each prefix policy runs its own subtask";
  EXPECT_GT(manipulate.calls[1], 0);
  EXPECT_EQ(e.prefix_steps, approach.calls[0] + manipulate.calls[1]);
  EXPECT_EQ(expert.calls[2], static_cast<int>(e.segment.size()));
  EXPECT_EQ(e.env_steps, e.prefix_steps + static_cast<int>(e.segment.size()));
  EXPECT_TRUE(e.subtask_done) << "scripted everywhere: retract places the block";
}

TEST(SubtaskRollout, ThePrefixDecidesWhereTheExpertStarts) {
  // The same episode seed after the scripted prefix and after a prefix that does nothing
  // (idle): the manipulate segment starts from different states.
  class Idle final : public sim::SubtaskPolicy {
   public:
    sim::Action act(sim::Subtask, const sim::Observation&, const sim::Goal&,
                    const sim::TaskState&) override {
      return sim::idle_action();
    }
    std::unique_ptr<sim::SubtaskPolicy> clone() const override { return std::make_unique<Idle>(); }
  };
  sim::PickPlaceEnv env(fetch_block());
  sim::ScriptedPolicy scripted;
  Idle idle;
  Rng rng(0);
  const auto after_scripted = run_subtask_episode(
      env, sim::Subtask::kManipulate, {&scripted, &scripted, &scripted}, scripted, nullptr, 9, rng);
  const auto after_idle = run_subtask_episode(
      env, sim::Subtask::kManipulate, {&idle, &scripted, &scripted}, scripted, nullptr, 9, rng);
  EXPECT_EQ(after_idle.prefix_steps, sim::step_cap(sim::Subtask::kApproach))
      << "an approach that never arrives runs to its cap";
  EXPECT_LT(after_scripted.prefix_steps, after_idle.prefix_steps);
  EXPECT_FALSE(
      after_scripted.segment.front().observation.isApprox(after_idle.segment.front().observation));
}

TEST(HlcOptions, ASubtaskWhosePredicateHoldsCannotBeChosen) {
  sim::PickPlaceEnv env(fetch_block());
  env.reset(derive_seed(2, 0));
  EXPECT_EQ(available_subtasks(env.task_state()), (std::array<bool, 3>{true, true, true}));
  // Run the scripted approach to its predicate: approach is then unavailable.
  for (int t = 0; t < sim::step_cap(sim::Subtask::kApproach); ++t) {
    const sim::TaskState s = env.task_state();
    const auto r =
        env.step(sim::scripted_action(sim::Subtask::kApproach, s),
                 sim::objective_goal(sim::Objective::kApproach, s), sim::Objective::kApproach);
    if (r.objective_done) break;
  }
  EXPECT_EQ(available_subtasks(env.task_state()), (std::array<bool, 3>{false, true, true}));
}

TEST(HlcOptions, UnavailableSubtasksGetZeroProbabilityAndTheRestSumToOne) {
  const auto p = masked_softmax({5.0, 1.0, 1.0}, {false, true, true});
  EXPECT_EQ(p[0], 0.0) << "the largest logit is masked out";
  EXPECT_NEAR(p[1], 0.5, 1e-12);
  EXPECT_NEAR(p[1] + p[2], 1.0, 1e-12);
}

}  // namespace
}  // namespace pnp::rl
