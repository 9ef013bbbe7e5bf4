#include "sim/subtask.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "sim/scripted_expert.h"
#include "sim/subtask_sequence.h"
#include "sim/world_layout.h"

namespace pnp::sim {
namespace {

TaskState state_with(const Eigen::Vector3d& gripper, const Eigen::Vector3d& object,
                     double gap = 0.1) {
  return {gripper, object, gap, Eigen::Vector3d(1.4, 0.8, 0.5), 0.05};
}

const Eigen::Vector3d kObject(1.3, 0.7, 0.425);

TEST(Approach, GoalIsThePreGraspPointAboveTheObject) {
  const TaskState s = state_with({1.3, 0.75, 0.6}, kObject);
  EXPECT_EQ(objective_goal(Objective::kApproach, s), kObject + Eigen::Vector3d(0, 0, 0.03));
  EXPECT_EQ(achieved_goal(Objective::kApproach, s), s.gripper);
}

TEST(Approach, DoneWithinTheToleranceOfThePreGraspPoint) {
  const Eigen::Vector3d pre = kObject + Eigen::Vector3d(0, 0, thresholds::kPreGraspHeight_m);
  EXPECT_TRUE(objective_done(Objective::kApproach,
                             state_with(pre + Eigen::Vector3d(0.019, 0, 0), kObject)));
  EXPECT_FALSE(objective_done(Objective::kApproach,
                              state_with(pre + Eigen::Vector3d(0.021, 0, 0), kObject)));
}

TEST(Approach, NotDoneWithTheFingersClosed) {
  const Eigen::Vector3d pre = kObject + Eigen::Vector3d(0, 0, thresholds::kPreGraspHeight_m);
  const double width = 0.05;  // state_with's object
  EXPECT_FALSE(objective_done(Objective::kApproach, state_with(pre, kObject, 0.0)));
  EXPECT_FALSE(
      objective_done(Objective::kApproach,
                     state_with(pre, kObject, width + thresholds::kPreGraspOpening_m - 0.001)))
      << "pads not clear of the object";
  EXPECT_TRUE(
      objective_done(Objective::kApproach,
                     state_with(pre, kObject, width + thresholds::kPreGraspOpening_m + 0.001)));
}

TEST(Manipulate, DoneOnlyWhenCentredAndClosedOnTheObject) {
  const Eigen::Vector3d near = kObject + Eigen::Vector3d(0, 0, 0.01);
  EXPECT_TRUE(objective_done(Objective::kManipulate, state_with(near, kObject, 0.051)));
  EXPECT_FALSE(objective_done(Objective::kManipulate, state_with(near, kObject, 0.1)))
      << "open fingers are no grasp";
  EXPECT_FALSE(objective_done(Objective::kManipulate,
                              state_with(kObject + Eigen::Vector3d(0, 0, 0.02), kObject, 0.05)))
      << "closed above the object is no grasp";
  EXPECT_EQ(objective_goal(Objective::kManipulate, state_with(near, kObject)), kObject);
}

TEST(Retract, ScoredOnTheObjectAgainstTheEpisodeGoal) {
  TaskState s = state_with(kObject, kObject, 0.05);
  EXPECT_EQ(objective_goal(Objective::kRetract, s), s.episode_goal);
  EXPECT_EQ(achieved_goal(Objective::kRetract, s), s.object);
  EXPECT_FALSE(objective_done(Objective::kRetract, s));
  s.object = s.episode_goal + Eigen::Vector3d(0, 0.009, 0);
  s.gripper = s.object + Eigen::Vector3d(0, 0, 0.02);  // held, shifted in the hand
  EXPECT_TRUE(objective_done(Objective::kRetract, s));
  s.gripper = s.episode_goal;  // the gripper at the goal does not count
  s.object = kObject;
  EXPECT_FALSE(objective_done(Objective::kRetract, s));
}

TEST(Retract, ADroppedObjectAtTheGoalIsNotDone) {
  TaskState s = state_with(kObject, kObject, 0.05);
  s.object = s.episode_goal;
  s.gripper = s.object + Eigen::Vector3d(0, 0, 0.05);  // let go above it
  s.finger_gap_m = 0.0;
  EXPECT_FALSE(objective_done(Objective::kRetract, s));
  s.gripper = s.object;
  s.finger_gap_m = 0.1;  // opened around it
  EXPECT_FALSE(objective_done(Objective::kRetract, s));
  s.finger_gap_m = 0.05;
  EXPECT_TRUE(objective_done(Objective::kRetract, s));
}

TEST(StepCaps, DefinedOncePerSubtaskAndScaledWithTheEpisode) {
  EXPECT_EQ(step_cap(Subtask::kApproach, 50), thresholds::kApproachStepCap);
  EXPECT_EQ(step_cap(Subtask::kManipulate, 50), thresholds::kManipulateStepCap);
  EXPECT_EQ(step_cap(Subtask::kRetract, 50), thresholds::kRetractStepCap);
  // The arm's 75 steps: half as long again, rounded down; retract keeps the rest.
  EXPECT_EQ(step_cap(Subtask::kApproach, 75), 30);
  EXPECT_EQ(step_cap(Subtask::kManipulate, 75), 22);
  EXPECT_EQ(step_cap(Subtask::kRetract, 75), 75);
  EXPECT_EQ(step_cap(Subtask::kManipulate, 1), 1) << "a cap is at least one step";
  EXPECT_EQ(step_caps(75), (StepCaps{30, 22, 75})) << "indexed by Subtask, as step_cap gives them";
  try {
    step_cap(Subtask::kApproach, 0);
    FAIL() << "an empty episode got a cap";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("episode_steps"), std::string::npos) << e.what();
  }
}

TEST(Names, ParseRefusesUnknownNamesNamingTheField) {
  EXPECT_EQ(parse_subtask("retract"), Subtask::kRetract);
  EXPECT_EQ(parse_objective("task"), Objective::kTask);
  try {
    parse_subtask("grasp", "role");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "role: expected one of approach, manipulate, retract, got \"grasp\"");
  }
}

TEST(ScriptedExperts, ProportionalWithGainSixClippedToOne) {
  const TaskState s = state_with(kObject + Eigen::Vector3d(0.1, -0.01, 0.03), kObject);
  const Action a = scripted_action(Subtask::kApproach, s);
  EXPECT_NEAR(a(0), -0.6, 1e-12);
  EXPECT_NEAR(a(1), 0.06, 1e-12);
  EXPECT_NEAR(a(2), 0.0, 1e-12);
  EXPECT_EQ(a(3), 1.0);  // approach keeps the gripper open
  const Action far =
      scripted_action(Subtask::kApproach, state_with(kObject + Eigen::Vector3d(1, 0, 0), kObject));
  EXPECT_EQ(far(0), -1.0);
}

TEST(ScriptedExperts, ManipulateClosesOnlyOnceCentred) {
  EXPECT_EQ(scripted_action(Subtask::kManipulate,
                            state_with(kObject + Eigen::Vector3d(0, 0, 0.03), kObject))(3),
            1.0);
  EXPECT_EQ(scripted_action(Subtask::kManipulate,
                            state_with(kObject + Eigen::Vector3d(0, 0, 0.01), kObject))(3),
            -1.0);
}

TEST(ScriptedExperts, RetractMovesTheObjectTowardsTheGoalWithTheGripperClosed) {
  const TaskState s = state_with(kObject + Eigen::Vector3d(0, 0, 0.008), kObject, 0.05);
  const Action a = scripted_action(Subtask::kRetract, s);
  const Eigen::Vector3d expected = (6 * (s.episode_goal - s.object)).cwiseMax(-1).cwiseMin(1);
  EXPECT_TRUE(a.head<3>().isApprox(expected));
  EXPECT_EQ(a(3), -1.0);
  EXPECT_EQ(idle_action(), Action(0, 0, 0, -1));
}

}  // namespace
}  // namespace pnp::sim

namespace pnp::sim {
namespace {

TEST(SubtaskSequence, AdvancesOnThePredicateOrTheCapThenIdles) {
  SubtaskSequence s(layout::kEpisodeSteps);
  EXPECT_EQ(s.current(), Subtask::kApproach);
  EXPECT_FALSE(s.record_step(false));
  EXPECT_TRUE(s.record_step(true));  // predicate fired
  EXPECT_EQ(s.current(), Subtask::kManipulate);
  for (int t = 1; t < thresholds::kManipulateStepCap; ++t) EXPECT_FALSE(s.record_step(false));
  EXPECT_TRUE(s.record_step(false));  // cap reached
  EXPECT_EQ(s.objective(), Objective::kRetract);
  EXPECT_TRUE(s.record_step(true));
  EXPECT_TRUE(s.idle());
  EXPECT_EQ(s.objective(), Objective::kTask);
  EXPECT_FALSE(s.record_step(true)) << "idle: nothing left to end";
}

TEST(SubtaskSequence, TheArmsLongerEpisodeGivesManipulateItsLongerCap) {
  SubtaskSequence s(layout::kArmEpisodeSteps);
  EXPECT_TRUE(s.record_step(true));  // approach
  const int cap = step_cap(Subtask::kManipulate, layout::kArmEpisodeSteps);
  ASSERT_GT(cap, thresholds::kManipulateStepCap);
  for (int t = 1; t < cap; ++t) EXPECT_FALSE(s.record_step(false)) << t;
  EXPECT_TRUE(s.record_step(false));
  EXPECT_EQ(s.current(), Subtask::kRetract);
}

}  // namespace
}  // namespace pnp::sim
