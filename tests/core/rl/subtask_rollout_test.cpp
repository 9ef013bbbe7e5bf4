#include "rl/subtask_rollout.h"

#include <gtest/gtest.h>

#include <limits>
#include <memory>
#include <span>
#include <utility>

#include "common/error.h"
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

// Runs the scripted expert of `subtask` until its predicate holds or its step cap.
void run_scripted_to_predicate(sim::PickPlaceEnv& env, sim::Subtask subtask) {
  const sim::Objective objective = sim::objective_of(subtask);
  for (int t = 0; t < sim::step_cap(subtask, env.episode_steps()); ++t) {
    const sim::TaskState s = env.task_state();
    if (sim::objective_done(objective, s)) return;
    env.step(sim::scripted_action(subtask, s), sim::objective_goal(objective, s), objective);
  }
}

// A PickPlaceEnv whose object's velocity blows up before step `fault_at`, as a contact
// instability would: the environment reports the fault and has already begun a fresh
// episode, with another goal.
class FaultAtStep final : public sim::Environment {
 public:
  FaultAtStep(std::shared_ptr<const sim::WorldModel> world, int fault_at)
      : env_(std::move(world)), fault_at_(fault_at) {}
  using sim::Environment::step;
  const sim::Observation& reset(std::uint64_t seed) override {
    steps_ = 0;
    return env_.reset(seed);
  }
  sim::StepResult step(std::span<const double> action, std::span<const double> goal,
                       sim::Objective objective) override {
    if (steps_++ == fault_at_)
      env_.mj_data()->qvel[env_.world().ids().object_dof] =
          std::numeric_limits<double>::quiet_NaN();
    return env_.step(action, goal, objective);
  }
  const sim::Observation& observation() const override { return env_.observation(); }
  const sim::Goal& episode_goal() const override { return env_.episode_goal(); }
  sim::TaskState task_state() const override { return env_.task_state(); }
  int elapsed_steps() const override { return env_.elapsed_steps(); }
  bool needs_reset() const override { return env_.needs_reset(); }
  int episode_steps() const override { return env_.episode_steps(); }

 private:
  sim::PickPlaceEnv env_;
  int fault_at_, steps_ = 0;
};

// One termination rule: on real episodes with training noise, every stored transition's
// done (recomputed by the replay with the goal acted on) equals the environment's (a
// segment ends at the environment's first done, so only its last transition may be
// terminal, and is exactly when the subtask's predicate fired).
TEST(SubtaskRollout, EveryStoredDoneEqualsTheEnvironmentsOnNoisyEpisodes) {
  const auto world = fetch_block();
  sim::PickPlaceEnv env(world);
  sim::ScriptedPolicy scripted;
  const ExplorationNoise noise;
  Rng rng(11);
  for (sim::Subtask subtask : sim::kAllSubtasks) {
    SegmentReplay replay(100'000, sim::objective_of(subtask),
                         2 * world->object_spec().half_width_m);
    std::size_t index = 0;
    int terminals = 0;
    for (std::uint64_t e = 0; e < 60; ++e) {
      const SubtaskEpisode episode =
          run_subtask_episode(env, subtask, {&scripted, &scripted, &scripted}, scripted, &noise,
                              derive_seed(17, e), rng);
      replay.add_segment(episode.segment);
      for (std::size_t t = 0; t < episode.segment.size(); ++t, ++index) {
        const bool env_done = episode.subtask_done && t + 1 == episode.segment.size();
        ASSERT_EQ(replay.done_for(index, episode.segment[t].goal), env_done ? 1.0f : 0.0f)
            << sim::subtask_name(subtask) << " episode " << e << " step " << t;
      }
      terminals += episode.subtask_done ? 1 : 0;
    }
    EXPECT_GT(terminals, 10) << sim::subtask_name(subtask) << ": too few terminals to judge";
  }
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
  EXPECT_EQ(after_idle.prefix_steps, sim::step_cap(sim::Subtask::kApproach, env.episode_steps()))
      << "an approach that never arrives runs to its cap";
  EXPECT_LT(after_scripted.prefix_steps, after_idle.prefix_steps);
  EXPECT_FALSE(
      after_scripted.segment.front().observation.isApprox(after_idle.segment.front().observation));
}

TEST(HlcOptions, ASubtaskWhosePredicateHoldsCannotBeChosen) {
  sim::PickPlaceEnv env(fetch_block());
  env.reset(derive_seed(2, 0));
  EXPECT_EQ(available_subtasks(env.task_state(), true), (std::array<bool, 3>{true, true, true}));
  // Run the scripted approach to its predicate: approach is then unavailable.
  run_scripted_to_predicate(env, sim::Subtask::kApproach);
  EXPECT_EQ(available_subtasks(env.task_state(), true), (std::array<bool, 3>{false, true, true}));
  EXPECT_EQ(available_subtasks(env.task_state(), false), (std::array<bool, 3>{true, true, true}))
      << "the paper's choreographer may choose any subtask at any decision";
}

// Probabilities that sum to a little under 1 (rounding) must not let a draw past them
// pick a masked-out subtask (it picked the last, retract, whatever its mask).
TEST(HlcOptions, ADrawPastTheRoundedSumNeverPicksAMaskedOutSubtask) {
  Rng rng(5);
  const std::array<double, 3> p{0.3, 0.3, 0.0};  // an extreme of rounding: u > 0.6 falls off
  int second = 0;
  for (int i = 0; i < 1000; ++i) {
    const int choice = choose_subtask(p, true, rng);
    ASSERT_NE(choice, 2);
    second += choice == 1 ? 1 : 0;
  }
  EXPECT_GT(second, 500);  // draws past the sum went to the last available subtask
  EXPECT_EQ(choose_subtask({0.2, 0.7, 0.1}, false, rng), 1);
}

// The A3C normaliser learns from an episode's decision inputs with the episode's goal: the
// episode keeps it, since after a fault the environment already holds the next one's.
TEST(HlcEpisode, KeepsTheGoalItWasPlayedForAfterAFaultReset) {
  const std::uint64_t seed = derive_seed(3, 0);
  sim::PickPlaceEnv reference(fetch_block());
  reference.reset(seed);
  const sim::Goal goal = reference.episode_goal();

  FaultAtStep env(fetch_block(), 5);
  ChoreographerNet net({{16}, 4});
  Rng init(1), choices(2);
  net.initialise(init);
  sim::ScriptedPolicy scripted;
  const HlcEpisode episode =
      run_hlc_episode(env, net, {&scripted, &scripted, &scripted}, seed, true, choices);
  EXPECT_FALSE(episode.success);
  EXPECT_EQ(episode.env_steps, 6);
  EXPECT_EQ(episode.goal, goal);
  EXPECT_NE(env.episode_goal(), goal) << "the environment moved on to a fresh episode";
}

// An exploring start draws each available subtask alike, whatever the policy prefers.
TEST(HlcOptions, AnExploringStartDrawsEveryAvailableSubtaskAlike) {
  Rng rng(9);
  std::array<int, 3> all{}, two{};
  for (int i = 0; i < 3000; ++i) {
    ++all[static_cast<std::size_t>(choose_uniformly({true, true, true}, rng))];
    ++two[static_cast<std::size_t>(choose_uniformly({false, true, true}, rng))];
  }
  for (int count : all) EXPECT_NEAR(count, 1000, 100);
  EXPECT_EQ(two[0], 0) << "a masked-out subtask was drawn";
  EXPECT_NEAR(two[1], 1500, 120);
  EXPECT_THROW(choose_uniformly({false, false, false}, rng), Error);
}

// Only the first decision of an exploring start is drawn uniformly (and flagged so A3C
// leaves it out of the losses); the policy makes every later one.
TEST(HlcEpisode, AnExploringStartFlagsItsFirstDecisionOnly) {
  ChoreographerNet net({{16}, 4});
  Rng init(1);
  net.initialise(init);
  sim::PickPlaceEnv env(fetch_block());
  sim::ScriptedPolicy scripted;
  std::array<int, 3> first{};
  Rng choices(4);
  for (std::uint64_t e = 0; e < 30; ++e) {
    const HlcEpisode episode = run_hlc_episode(env, net, {&scripted, &scripted, &scripted},
                                               derive_seed(6, e), true, choices, true);
    ASSERT_FALSE(episode.decisions.empty());
    EXPECT_TRUE(episode.decisions.front().exploring);
    for (std::size_t d = 1; d < episode.decisions.size(); ++d)
      EXPECT_FALSE(episode.decisions[d].exploring);
    ++first[static_cast<std::size_t>(episode.decisions.front().choice)];
  }
  for (int count : first) EXPECT_GT(count, 3) << "every subtask opens some exploring starts";
  const HlcEpisode on_policy = run_hlc_episode(env, net, {&scripted, &scripted, &scripted},
                                               derive_seed(6, 99), true, choices);
  for (const HlcDecision& d : on_policy.decisions) EXPECT_FALSE(d.exploring);
}

// The chain prior adds its bonus to the subtask after the furthest one finished: approach
// at the start, manipulate once reached; the learned logits can outweigh it.
TEST(HlcOptions, TheChainPriorFavoursTheSubtaskAfterTheFurthestFinished) {
  sim::PickPlaceEnv env(fetch_block());
  env.reset(derive_seed(3, 0));
  ChoreographerSpec spec;
  spec.chain_prior = 2.0;
  const std::array<double, 3> flat{};
  const double favoured = std::exp(2.0) / (std::exp(2.0) + 2.0);
  auto p = decision_probabilities(flat, env.task_state(), spec);
  EXPECT_NEAR(p[0], favoured, 1e-12) << "approach first";
  EXPECT_NEAR(p[1], p[2], 1e-12);
  p = decision_probabilities({0.0, 3.0, 0.0}, env.task_state(), spec);
  EXPECT_GT(p[1], p[0]) << "a learned logit outweighs the prior";
  spec.chain_prior = 0;
  EXPECT_NEAR(decision_probabilities(flat, env.task_state(), spec)[0], 1.0 / 3, 1e-12);

  run_scripted_to_predicate(env, sim::Subtask::kApproach);
  ASSERT_TRUE(sim::objective_done(sim::Objective::kApproach, env.task_state()));
  spec.chain_prior = 2.0;
  p = decision_probabilities(flat, env.task_state(), spec);
  EXPECT_EQ(p[0], 0.0) << "approach is finished and masked";
  EXPECT_NEAR(p[1], std::exp(2.0) / (std::exp(2.0) + 1.0), 1e-12) << "manipulate next";

  run_scripted_to_predicate(env, sim::Subtask::kManipulate);
  ASSERT_TRUE(sim::objective_done(sim::Objective::kManipulate, env.task_state()));
  ASSERT_FALSE(sim::objective_done(sim::Objective::kApproach, env.task_state()))
      << "the grasp lifted the hand off approach's point: the case the rule is for";
  p = decision_probabilities(flat, env.task_state(), spec);
  EXPECT_NEAR(p[2], std::exp(2.0) / (std::exp(2.0) + 1.0), 1e-12)
      << "retract next, not the unfinished approach";
}

TEST(HlcOptions, UnavailableSubtasksGetZeroProbabilityAndTheRestSumToOne) {
  const auto p = masked_softmax({5.0, 1.0, 1.0}, {false, true, true});
  EXPECT_EQ(p[0], 0.0) << "the largest logit is masked out";
  EXPECT_NEAR(p[1], 0.5, 1e-12);
  EXPECT_NEAR(p[1] + p[2], 1.0, 1e-12);
}

}  // namespace
}  // namespace pnp::rl
