#include "rl/segment_replay.h"

#include <gtest/gtest.h>

#include <set>

#include "common/error.h"

namespace pnp::rl {
namespace {

// A segment whose gripper moves along x from x0 by 0.01 per step, fingers open (approach
// objective: achieved goal = gripper position).
std::vector<Transition> segment(double x0, int length, const sim::Goal& goal) {
  std::vector<Transition> out;
  for (int t = 0; t < length; ++t) {
    Transition tr;
    tr.observation = sim::Observation::Zero();
    tr.observation(sim::obs::kGripperPos) = x0 + 0.01 * t;
    tr.next_observation = sim::Observation::Zero();
    tr.next_observation(sim::obs::kGripperPos) = x0 + 0.01 * (t + 1);
    for (sim::Observation* o : {&tr.observation, &tr.next_observation})
      (*o)(sim::obs::kFingerPos) = (*o)(sim::obs::kFingerPos + 1) = 0.05;
    tr.action = sim::Action(0.2, 0, 0, 1);
    tr.goal = goal;
    out.push_back(tr);
  }
  return out;
}

TEST(SegmentReplay, HindsightGoalsComeOnlyFromLaterStepsOfTheSameSegment) {
  SegmentReplay replay(1000, sim::Objective::kApproach, 0.05);
  replay.add_segment(segment(0.0, 5, {9, 9, 9}));   // achieved x in 0.01 .. 0.05
  replay.add_segment(segment(10.0, 4, {9, 9, 9}));  // achieved x in 10.01 .. 10.04
  EXPECT_EQ(replay.size(), 9u);
  EXPECT_EQ(replay.steps_to_segment_end(0), 5u);
  EXPECT_EQ(replay.steps_to_segment_end(4), 1u);
  EXPECT_EQ(replay.steps_to_segment_end(5), 4u);
  Rng rng(1);
  SampledBatch batch;
  int relabelled = 0;
  for (int round = 0; round < 200; ++round) {
    replay.sample(32, 1.0, rng, batch);  // always relabel
    for (std::size_t i = 0; i < 32; ++i) {
      const double x = batch.observation[i * sim::kObservationSize];
      const double goal_x = batch.goal[i * sim::kGoalSize];
      const bool first_segment = x < 5;
      EXPECT_EQ(goal_x < 5, first_segment) << "a goal from another segment";
      EXPECT_GE(goal_x, x + 0.01 - 1e-6) << "a goal from an earlier step";
      ++relabelled;
    }
  }
  EXPECT_EQ(relabelled, 200 * 32);
}

TEST(SegmentReplay, RewardAndDoneAreRecomputedForTheRelabelledGoal) {
  SegmentReplay replay(100, sim::Objective::kApproach, 0.05);
  replay.add_segment(segment(0.0, 3, {1, 0, 0}));
  // Transition 0 reaches x = 0.01.
  EXPECT_FLOAT_EQ(replay.reward_for(0, {1, 0, 0}), -0.99f);
  EXPECT_EQ(replay.done_for(0, {1, 0, 0}), 0.0f);
  EXPECT_NEAR(replay.reward_for(0, {0.01, 0, 0}), 0.0f, 1e-6f);
  EXPECT_EQ(replay.done_for(0, {0.01, 0, 0}), 1.0f) << "the relabelled goal is reached: terminal";
  EXPECT_EQ(replay.done_for(0, {0.05, 0, 0}), 0.0f)
      << "4 cm away: beyond the 2 cm approach tolerance";
}

TEST(SegmentReplay, UnrelabelledSamplesKeepTheGoalActedOn) {
  SegmentReplay replay(100, sim::Objective::kApproach, 0.05);
  replay.add_segment(segment(0.0, 3, {0.7, 0.1, 0.2}));
  Rng rng(2);
  SampledBatch batch;
  replay.sample(16, 0.0, rng, batch);
  EXPECT_EQ(batch.relabelled, 0);
  for (std::size_t i = 0; i < 16; ++i) {
    EXPECT_FLOAT_EQ(batch.goal[i * 3], 0.7f);
    EXPECT_FLOAT_EQ(batch.goal[i * 3 + 1], 0.1f);
  }
}

TEST(SegmentReplay, OverwritesOldestFirstAndRefusesOversizedSegments) {
  SegmentReplay replay(6, sim::Objective::kApproach, 0.05);
  replay.add_segment(segment(0.0, 4, {1, 0, 0}));
  replay.add_segment(segment(10.0, 4, {1, 0, 0}));
  EXPECT_EQ(replay.size(), 6u);
  EXPECT_THROW(replay.add_segment(segment(0.0, 7, {1, 0, 0})), Error);
  SegmentReplay empty(4, sim::Objective::kApproach, 0.05);
  Rng rng(0);
  SampledBatch batch;
  EXPECT_THROW(empty.sample(2, 0.8, rng, batch), Error);
}

TEST(SegmentReplay, FutureProbabilityForK4IsEightyPercent) {
  EXPECT_DOUBLE_EQ(future_probability(4), 0.8);
  EXPECT_DOUBLE_EQ(future_probability(0), 0.0);
}

}  // namespace
}  // namespace pnp::rl

namespace pnp::rl {
namespace {

TEST(SegmentReplay, SparseRewardForTheEndToEndBaseline) {
  // Task objective: the achieved goal is the object, reward -1 until within 0.05 m.
  SegmentReplay replay(100, sim::Objective::kTask, 0.05, RewardKind::kSparse);
  std::vector<Transition> seg(1);
  seg[0].observation = sim::Observation::Zero();
  seg[0].next_observation = sim::Observation::Zero();
  seg[0].next_observation(sim::obs::kObjectPos) = 1.0;
  seg[0].goal = sim::Goal(1.0, 0, 0);
  seg[0].action = sim::Action::Zero();
  replay.add_segment(seg);
  EXPECT_EQ(replay.reward_for(0, {1.04, 0, 0}), 0.0f);
  EXPECT_EQ(replay.reward_for(0, {1.06, 0, 0}), -1.0f);
  EXPECT_EQ(replay.done_for(0, {1.0, 0, 0}), 0.0f) << "the whole task never terminates early";
}

}  // namespace
}  // namespace pnp::rl
