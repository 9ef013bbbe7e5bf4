#include "sim/gripper_script.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"

namespace pnp::sim {
namespace {

TaskState state_with_gripper_at(double distance_to_object_m) {
  TaskState s;
  s.object = {1.3, 0.75, 0.425};
  s.gripper = s.object + Eigen::Vector3d(0, 0, distance_to_object_m);
  s.finger_gap_m = 0.08;
  s.episode_goal = {1.3, 0.8, 0.6};
  s.object_width_m = 0.05;
  return s;
}

// The paper's code overwrote the gripper with a constant per subtask: manipulate closes
// from its first step, wherever the hand is; our grasp rule waits until it is centred.
TEST(GripperScript, PerSubtaskIsAConstantAndTheGraspRuleWaitsUntilCentred) {
  const TaskState far = state_with_gripper_at(0.03), centred = state_with_gripper_at(0.005);
  for (const TaskState& s : {far, centred}) {
    EXPECT_EQ(scripted_gripper(GripperScript::kPerSubtask, Subtask::kApproach, s), 1.0);
    EXPECT_EQ(scripted_gripper(GripperScript::kPerSubtask, Subtask::kManipulate, s), -1.0);
    EXPECT_EQ(scripted_gripper(GripperScript::kPerSubtask, Subtask::kRetract, s), -1.0);
    EXPECT_EQ(scripted_gripper(GripperScript::kGraspRule, Subtask::kApproach, s), 1.0);
    EXPECT_EQ(scripted_gripper(GripperScript::kGraspRule, Subtask::kRetract, s), -1.0);
  }
  EXPECT_EQ(scripted_gripper(GripperScript::kGraspRule, Subtask::kManipulate, far), 1.0);
  EXPECT_EQ(scripted_gripper(GripperScript::kGraspRule, Subtask::kManipulate, centred), -1.0);
}

TEST(GripperScript, NamesRoundTripAndAnUnknownOneIsRefusedNamingTheField) {
  for (GripperScript g : kAllGripperScripts)
    EXPECT_EQ(parse_gripper_script(gripper_script_name(g)), g);
  try {
    parse_gripper_script("always_open", "--gripper-script");
    FAIL() << "an unknown script was parsed";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "--gripper-script: expected one of grasp_rule, per_subtask, got \"always_open\"");
  }
}

}  // namespace
}  // namespace pnp::sim
