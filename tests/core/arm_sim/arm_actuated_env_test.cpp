// The arm-actuated world: the Panda's hand moved by its controller, episodes and scoring
// as the mocap world's, and everything a step does a function of the seed and actions.

#include "arm_sim/arm_actuated_env.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "arm_sim/arm_env_factory.h"
#include "common/error.h"
#include "common/rng.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_expert.h"
#include "sim/scripted_pipeline.h"
#include "sim/subtask.h"
#include "sim/world_layout.h"
#include "sim/world_model.h"

namespace pnp::arm_sim {
namespace {

using sim::Objective;
using sim::ObjectShape;
using sim::Robot;
using sim::WorldProfile;

std::shared_ptr<const sim::WorldModel> panda(WorldProfile profile = WorldProfile::kGym) {
  return sim::WorldModel::load(Robot::kPanda, ObjectShape::kBlock, profile);
}

const sim::Goal kAnyGoal{1.3, 0.75, 0.45};

TEST(ArmActuatedEnv, AnEpisodeHasTheMocapWorldsObjectAndGoalForItsSeed) {
  const auto world = panda();
  ArmActuatedEnv arm(world);
  sim::PickPlaceEnv mocap(world);
  for (std::uint64_t seed : {0ULL, 7ULL, 123456789ULL}) {
    const sim::Observation& a = arm.reset(seed);
    const sim::Observation& m = mocap.reset(seed);
    // The frames differ by the gateway's round trip (base frame and back): a few ulps.
    EXPECT_LT((sim::object_position(a) - sim::object_position(m)).norm(), 1e-9) << seed;
    EXPECT_LT((arm.episode_goal() - mocap.episode_goal()).norm(), 1e-9) << seed;
    // Both start from the same home pose: the grip point where the mocap world's is.
    EXPECT_LT((sim::gripper_position(a) - sim::gripper_position(m)).norm(), 1e-3) << seed;
    EXPECT_EQ(arm.elapsed_steps(), 0);
    EXPECT_FALSE(arm.needs_reset());
  }
}

TEST(ArmActuatedEnv, TheSameSeedAndActionsGiveTheSameEpisodeBitForBit) {
  const auto world = panda();
  ArmActuatedEnv a(world), b(world);
  a.reset(42);
  b.reset(42);
  for (int step = 0; step < 20; ++step) {
    const sim::Action action(std::sin(step), std::cos(step), -0.5, step % 3 ? 1 : -1);
    const sim::StepResult ra = a.step(action, kAnyGoal, Objective::kTask);
    const sim::StepResult rb = b.step(action, kAnyGoal, Objective::kTask);
    ASSERT_EQ(ra.observation, rb.observation) << "step " << step;
    ASSERT_EQ(ra.reward, rb.reward);
  }
}

// The point of the world: a 5 cm command is not reached in one 40 ms step, as on the
// real arm at its datasheet accelerations; the hand gathers speed over a few steps, and
// a zero action (the target where the hand is, as gym reads it) stops it.
TEST(ArmActuatedEnv, TheHandLagsBehindFullCommandsGathersSpeedAndStops) {
  const auto world = panda();
  ArmActuatedEnv env(world);
  sim::PickPlaceEnv mocap(world);
  Eigen::Vector3d previous = sim::gripper_position(env.reset(3));
  const double start_mocap = sim::gripper_position(mocap.reset(3)).z();
  const sim::Action up(0, 0, 1, 0);
  const sim::StepResult first = env.step(up, kAnyGoal, Objective::kTask);
  const double rise = first.observation(2) - previous.z();
  const double rise_mocap = mocap.step(up, kAnyGoal, Objective::kTask).observation(2) - start_mocap;
  EXPECT_GT(rise, 0.0005);
  EXPECT_LT(rise, 0.5 * rise_mocap) << "the arm kept up with the mocap hand";
  // The observation's velocity is the change over the step, as the gateway measures it.
  EXPECT_NEAR(first.observation(sim::obs::kGripperVel + 2), rise, 1e-12);
  previous = sim::gripper_position(first.observation);
  double fastest = rise;
  for (int step = 0; step < 6; ++step) {
    const sim::StepResult r = env.step(up, kAnyGoal, Objective::kTask);
    fastest = std::max(fastest, r.observation(2) - previous.z());
    previous = sim::gripper_position(r.observation);
  }
  EXPECT_GT(fastest, 0.01) << "the arm never got up to speed";
  EXPECT_LT(fastest, sim::layout::kActionPositionScale);
  sim::StepResult r;
  for (int step = 0; step < 8; ++step) r = env.step({0, 0, 0, 0}, kAnyGoal, Objective::kTask);
  EXPECT_LT(r.observation.segment<3>(sim::obs::kGripperVel).norm(), 1e-3);
}

TEST(ArmActuatedEnv, TheGripperOpensAndClosesByTheActionAsTheGatewayCommandsIt) {
  ArmActuatedEnv env(panda());
  const sim::Observation& start = env.reset(5);
  EXPECT_LT(sim::finger_gap(start), 0.005);  // gym: closed at reset
  // The Franka Hand's 70 N against the servo's damping: about 0.14 m/s of opening, as
  // slow as the real hand and slower than the mocap world's fingers.
  sim::StepResult r;
  for (int step = 0; step < 5; ++step) r = env.step({0, 0, 0, 1}, kAnyGoal, Objective::kTask);
  EXPECT_LT(sim::finger_gap(r.observation), 0.04);
  for (int step = 0; step < 10; ++step) r = env.step({0, 0, 0, 1}, kAnyGoal, Objective::kTask);
  EXPECT_GT(sim::finger_gap(r.observation), 0.07);
  // The Franka Hand's fingers are coupled: each finger is half the gap.
  EXPECT_EQ(r.observation(sim::obs::kFingerPos), r.observation(sim::obs::kFingerPos + 1));
  for (int step = 0; step < 15; ++step) r = env.step({0, 0, 0, -1}, kAnyGoal, Objective::kTask);
  EXPECT_LT(sim::finger_gap(r.observation), 0.005);
}

TEST(ArmActuatedEnv, AnEpisodeEndsAfterTheArmsSeventyFiveStepsAndBadInputChangesNothing) {
  ArmActuatedEnv env(panda());
  EXPECT_THROW(env.step({0, 0, 0, 0}, kAnyGoal, Objective::kTask), Error);  // before reset
  env.reset(1);
  const sim::Observation before = env.observation();
  const double nan = std::nan("");
  try {
    env.step({nan, 0, 0, 0}, kAnyGoal, Objective::kTask);
    FAIL() << "a NaN action was stepped";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("action"), std::string::npos) << e.what();
  }
  EXPECT_EQ(env.observation(), before);
  EXPECT_EQ(env.elapsed_steps(), 0);
  sim::StepResult r;
  // The arm's episode, longer than the mocap hand's.
  static_assert(sim::layout::kArmEpisodeSteps > sim::layout::kEpisodeSteps);
  for (int step = 0; step < sim::layout::kArmEpisodeSteps; ++step) {
    ASSERT_FALSE(r.episode_over) << step;
    r = env.step({0, 0, 0, 0}, kAnyGoal, Objective::kTask);
  }
  EXPECT_TRUE(r.episode_over);
  EXPECT_TRUE(env.needs_reset());
  try {
    env.step({0, 0, 0, 0}, kAnyGoal, Objective::kTask);
    FAIL() << "a step past the episode's end was taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
  }
}

// A command into the table is planned as the gateway plans it: kept inside the
// workspace, whose floor keeps the pads off the table; the hand never goes below it.
TEST(ArmActuatedEnv, ADiveIntoTheTableStopsAtTheWorkspaceFloor) {
  ArmActuatedEnv env(panda());
  env.reset(11);
  sim::StepResult r;
  double lowest = 1e9;
  for (int step = 0; step < 20; ++step) {
    r = env.step({0, 0, -1, 0}, kAnyGoal, Objective::kTask);
    lowest = std::min(lowest, r.observation(2));
  }
  EXPECT_EQ(r.fault, sim::PhysicsFault::kNone);
  EXPECT_GT(lowest, sim::layout::kTableTop_z);
  EXPECT_LT(lowest, sim::layout::kTableTop_z + 0.03);  // it does get down to the object
}

// The arm closes the Franka Hand slower than the mocap world's fingers: a scripted
// manipulate on the cylinder needs more than gym's 15 steps, and gets the arm's longer cap.
TEST(ArmActuatedEnv, ManipulateGetsTheArmsLongerStepCap) {
  ArmActuatedEnv env(
      sim::WorldModel::load(Robot::kPanda, ObjectShape::kCylinder, WorldProfile::kGym));
  sim::ScriptedPolicy scripted;
  const sim::SubtaskPolicies experts{&scripted, &scripted, &scripted};
  const int cap = sim::step_cap(sim::Subtask::kManipulate, env.episode_steps());
  ASSERT_GT(cap, sim::thresholds::kManipulateStepCap);
  int longest = 0;
  for (std::uint64_t i = 0; i < 8; ++i) {
    const sim::EpisodeOutcome o = sim::run_pipeline_episode(env, experts, derive_seed(0, i));
    longest =
        std::max(longest, o.subtask_steps[static_cast<std::size_t>(sim::Subtask::kManipulate)]);
  }
  EXPECT_GT(longest, sim::thresholds::kManipulateStepCap);
  EXPECT_LE(longest, cap);
}

TEST(ArmEnvFactory, MakesArmActuatedPandaWorldsAndRefusesFetchNamingActuation) {
  const auto envs = make_env_factory(Robot::kPanda, ObjectShape::kCylinder, WorldProfile::kPaper,
                                     sim::Actuation::kArm);
  EXPECT_EQ(envs->actuation(), sim::Actuation::kArm);
  EXPECT_EQ(envs->object(), ObjectShape::kCylinder);
  EXPECT_EQ(envs->profile(), WorldProfile::kPaper);
  EXPECT_NE(dynamic_cast<ArmActuatedEnv*>(envs->make().get()), nullptr);
  const auto mocap = make_env_factory(Robot::kFetch, ObjectShape::kBlock, WorldProfile::kGym,
                                      sim::Actuation::kMocap);
  EXPECT_EQ(mocap->actuation(), sim::Actuation::kMocap);
  EXPECT_NE(dynamic_cast<sim::PickPlaceEnv*>(mocap->make().get()), nullptr);
  try {
    make_env_factory(Robot::kFetch, ObjectShape::kBlock, WorldProfile::kGym, sim::Actuation::kArm);
    FAIL() << "an arm-actuated Fetch was made";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("actuation"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pnp::arm_sim
