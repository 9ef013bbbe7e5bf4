#include "sim/world_model.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "common/error.h"
#include "sim/inverse_kinematics.h"
#include "sim/mujoco_data.h"
#include "sim/panda_hand.h"
#include "sim/pick_place_env.h"
#include "sim/world_layout.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

class EveryWorld : public ::testing::TestWithParam<std::tuple<Robot, ObjectShape>> {};

TEST_P(EveryWorld, CompilesWithSevenArmJointsAndAGripper) {
  const auto [robot, object] = GetParam();
  const auto w = testing::world(robot, object);
  const mjModel* m = w->mj();
  EXPECT_EQ(m->opt.timestep, layout::kPhysicsTimestep_s);
  EXPECT_EQ(m->nmocap, 2);
  // 7 arm hinges + 2 finger slides + the object's free joint.
  EXPECT_EQ(m->njnt, 10);
  EXPECT_EQ(m->nu, 2);
  const double expected_range = robot == Robot::kFetch ? 0.05 : 0.04;
  EXPECT_DOUBLE_EQ(w->finger_range_m(), expected_range);
  const int object_geom = mj_name2id(m, mjOBJ_GEOM, "object");
  ASSERT_GE(object_geom, 0);
  EXPECT_NEAR(m->geom_size[3 * object_geom], w->object_spec().half_width_m, 1e-12);
  EXPECT_NEAR(m->body_mass[w->ids().object_body], w->object_spec().mass_kg, 1e-12);
}

TEST_P(EveryWorld, HomePoseHasTheGripAtTheStartPointingDown) {
  const auto [robot, object] = GetParam();
  const auto w = testing::world(robot, object);
  const mjModel* m = w->mj();
  DataPtr d = make_data(m);
  std::copy(w->home_qpos().begin(), w->home_qpos().end(), d->qpos);
  mj_kinematics(m, d.get());
  const int site = w->ids().grip_site;
  const Eigen::Vector3d grip(d->site_xpos[3 * site], d->site_xpos[3 * site + 1],
                             d->site_xpos[3 * site + 2]);
  EXPECT_LT((grip - layout::kGripperStart).norm(), 1e-3);
  // The site's z axis (third column of the row-major matrix) points down.
  EXPECT_NEAR(d->site_xmat[9 * site + 8], -1.0, 1e-3);
  // The fingers slide along world y: the site's y axis is horizontal along y.
  EXPECT_NEAR(std::abs(d->site_xmat[9 * site + 4]), 1.0, 1e-3);
}

TEST_P(EveryWorld, ArmJointLimitsAreThoseOfTheRealArm) {
  const auto [robot, object] = GetParam();
  const auto w = testing::world(robot, object);
  const mjModel* m = w->mj();
  const int first = w->ids().arm_joints[0];
  if (robot == Robot::kPanda) {
    EXPECT_DOUBLE_EQ(m->jnt_range[2 * first], -2.8973);
    const int j4 = w->ids().arm_joints[3];
    EXPECT_DOUBLE_EQ(m->jnt_range[2 * j4], -3.0718);
    EXPECT_DOUBLE_EQ(m->jnt_range[2 * j4 + 1], -0.0698);
  } else {
    EXPECT_DOUBLE_EQ(m->jnt_range[2 * first], -1.6056);
  }
}

INSTANTIATE_TEST_SUITE_P(AllWorlds, EveryWorld,
                         ::testing::Combine(::testing::Values(Robot::kFetch, Robot::kPanda),
                                            ::testing::Values(ObjectShape::kBlock,
                                                              ObjectShape::kSmallBlock,
                                                              ObjectShape::kCylinder)),
                         [](const auto& param_info) {
                           return std::string(robot_name(std::get<0>(param_info.param))) + "_" +
                                  std::string(object_name(std::get<1>(param_info.param)));
                         });

// Every point where an object or goal can be sampled in the paper world is reachable
// with the gripper pointing exactly down, within joint limits, on both arms. (Gym's
// goals reach 0.45 m: the Fetch arm reaches the highest ones nearest its base only with
// the gripper tilted, IK 0.14 rad off vertical; the test below drives it there.)
TEST(Reachability, EveryCornerOfThePaperSamplingRegionWithTheGripperDown) {
  for (WorldProfile profile : {WorldProfile::kPaper}) {
    const WorldParameters& p = world_parameters(profile);
    for (Robot robot : kAllRobots) {
      const auto w = WorldModel::load(robot, ObjectShape::kBlock, profile);
      const mjModel* m = w->mj();
      DataPtr d = make_data(m);
      const Eigen::Matrix3d down = Eigen::Quaterniond(0, 0, 1, 0).toRotationMatrix();
      std::array<double, kArmJoints> home{};
      for (std::size_t j = 0; j < kArmJoints; ++j)
        home[j] = w->home_qpos()[static_cast<std::size_t>(m->jnt_qposadr[w->ids().arm_joints[j]])];
      for (double dx : {-p.goal_range_m, p.goal_range_m}) {
        for (double dy : {-p.goal_range_m, p.goal_range_m}) {
          for (double z :
               {layout::kTableTop_z + 0.015, layout::kTableTop_z + 0.025 + p.goal_max_height_m}) {
            std::copy(w->home_qpos().begin(), w->home_qpos().end(), d->qpos);
            const Eigen::Vector3d target = p.gripper_start() + Eigen::Vector3d(dx, dy, 0);
            const IkResult r = solve_site_ik(m, d.get(), w->ids().grip_site, w->ids().arm_joints,
                                             {{target.x(), target.y(), z}, down}, home);
            EXPECT_LT(r.position_error_m, 1e-3)
                << world_profile_name(profile) << " " << robot_name(robot) << " " << dx << " " << dy
                << " " << z;
            EXPECT_LT(r.rotation_error_rad, 1e-2) << robot_name(robot);
          }
        }
      }
    }
  }
}

// Driven through the environment's own control (the mocap weld), the gripper gets to
// every top corner of the goal region of every world within an episode.
TEST(Reachability, TheGripperIsDrivenToEveryTopCornerOfTheGoalRegionInEveryWorld) {
  for (WorldProfile profile : kAllWorldProfiles) {
    const WorldParameters& p = world_parameters(profile);
    for (Robot robot : kAllRobots) {
      PickPlaceEnv env(WorldModel::load(robot, ObjectShape::kBlock, profile));
      for (double dx : {-p.goal_range_m, p.goal_range_m}) {
        for (double dy : {-p.goal_range_m, p.goal_range_m}) {
          env.reset(1);
          const Eigen::Vector3d corner =
              p.gripper_start() + Eigen::Vector3d(dx, dy, 0) +
              Eigen::Vector3d(
                  0, 0, layout::kTableTop_z + 0.025 + p.goal_max_height_m - p.gripper_start().z());
          for (int step = 0; step + 1 < layout::kEpisodeSteps; ++step) {
            Action a;
            a.head<3>() = (10.0 * (corner - env.task_state().gripper)).cwiseMax(-1.0).cwiseMin(1.0);
            a(3) = 0;
            env.step(a, corner, Objective::kTask);
          }
          EXPECT_LT((env.task_state().gripper - corner).norm(), 0.005)
              << world_profile_name(profile) << " " << robot_name(robot) << " " << dx << " " << dy;
        }
      }
    }
  }
}

// The grip point and the pads' reach the gateway and the controller rely on
// (sim/panda_hand.h) are the Panda model's, in every world.
TEST(PandaHand, TheModelsGripSiteAndPadsAreTheOneDefinition) {
  for (WorldProfile profile : kAllWorldProfiles) {
    const auto w = WorldModel::load(Robot::kPanda, ObjectShape::kBlock, profile);
    const mjModel* m = w->mj();
    const int site = mj_name2id(m, mjOBJ_SITE, "grip");
    const int hand = mj_name2id(m, mjOBJ_BODY, "gripper");  // at the flange
    ASSERT_GE(site, 0);
    ASSERT_EQ(m->site_bodyid[site], hand);
    EXPECT_NEAR(m->site_pos[3 * site + 2], kGripPointFromFlange_m, 1e-12);
    for (const char* pad : {"pad_left", "pad_right"}) {
      const int g = mj_name2id(m, mjOBJ_GEOM, pad);
      ASSERT_GE(g, 0);
      const double tip = m->geom_pos[3 * g + 2] + m->geom_size[3 * g + 2];  // in the finger frame
      EXPECT_NEAR(tip - kGripPointFromFlange_m, kPadReachBelowGripPoint_m, 5e-4) << pad;
    }
  }
}

TEST(Names, ParseAndPrintRoundTrip) {
  for (Robot r : kAllRobots) EXPECT_EQ(parse_robot(robot_name(r)), r);
  for (ObjectShape o : kAllObjectShapes) EXPECT_EQ(parse_object(object_name(o)), o);
  for (WorldProfile w : kAllWorldProfiles) EXPECT_EQ(parse_world_profile(world_profile_name(w)), w);
  EXPECT_THROW(parse_world_profile("mujoco", "--world"), pnp::Error);
}

}  // namespace
}  // namespace pnp::sim
