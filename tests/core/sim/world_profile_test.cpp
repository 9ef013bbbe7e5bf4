// The gym world differs from the paper world exactly where world_profile.h says, and the
// paper world is unchanged by the profile machinery.

#include "sim/world_profile.h"

#include <gtest/gtest.h>

#include <array>

#include "sim/pick_place_env.h"
#include "sim/world_layout.h"
#include "sim/world_model.h"

namespace pnp::sim {
namespace {

std::shared_ptr<const WorldModel> load(WorldProfile profile, Robot robot = Robot::kFetch,
                                       ObjectShape object = ObjectShape::kBlock) {
  return WorldModel::load(robot, object, profile);
}

TEST(WorldProfile, GymObjectsWeighTwentyTimesTheirPaperMassSoTheBlockWeighsTwoKilograms) {
  for (ObjectShape object : kAllObjectShapes) {
    const auto paper = load(WorldProfile::kPaper, Robot::kFetch, object);
    const auto gym = load(WorldProfile::kGym, Robot::kFetch, object);
    const double paper_kg = paper->mj()->body_mass[paper->ids().object_body];
    const double gym_kg = gym->mj()->body_mass[gym->ids().object_body];
    EXPECT_DOUBLE_EQ(paper_kg, object_spec(object).mass_kg) << object_name(object);
    EXPECT_DOUBLE_EQ(gym_kg, 20 * paper_kg) << object_name(object);
    EXPECT_DOUBLE_EQ(gym->object_spec().mass_kg, gym_kg) << object_name(object);
  }
  const auto gym_block = load(WorldProfile::kGym);
  EXPECT_DOUBLE_EQ(gym_block->mj()->body_mass[gym_block->ids().object_body], 2.0);
}

// MuJoCo's collision filter between two geoms.
bool can_touch(const mjModel* m, int a, int b) {
  return (m->geom_contype[a] & m->geom_conaffinity[b]) ||
         (m->geom_contype[b] & m->geom_conaffinity[a]);
}

bool in_subtree(const mjModel* m, int body, int root) {
  for (; body > 0; body = m->body_parentid[body]) {
    if (body == root) return true;
  }
  return root == 0;
}

// Bodies of the seven arm links (each carries one arm joint) whose geoms can touch the
// table; the gripper (the grip site's body and below) is not counted.
int arm_links_touching_the_table(const WorldModel& w) {
  const mjModel* m = w.mj();
  const int table = mj_name2id(m, mjOBJ_GEOM, "table");
  const int gripper = m->site_bodyid[w.ids().grip_site];
  int links = 0;
  for (int joint : w.ids().arm_joints) {
    const int body = m->jnt_bodyid[joint];
    bool touches = false;
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_bodyid[g] == body && !in_subtree(m, body, gripper) && can_touch(m, g, table)) {
        touches = true;
      }
    }
    links += touches ? 1 : 0;
  }
  return links;
}

TEST(WorldProfile, ArmLinksTouchTheTableAndObjectOnlyInGym) {
  for (Robot robot : kAllRobots) {
    EXPECT_EQ(arm_links_touching_the_table(*load(WorldProfile::kPaper, robot)), 0)
        << robot_name(robot);
    EXPECT_EQ(arm_links_touching_the_table(*load(WorldProfile::kGym, robot)), kArmJoints)
        << robot_name(robot);
  }
}

TEST(WorldProfile, ArmLinksNeverTouchEachOtherOrTheGripper) {
  for (Robot robot : kAllRobots) {
    const auto w = load(WorldProfile::kGym, robot);
    const mjModel* m = w->mj();
    const int root = w->ids().arm_root_body;
    for (int a = 0; a < m->ngeom; ++a) {
      for (int b = a + 1; b < m->ngeom; ++b) {
        if (in_subtree(m, m->geom_bodyid[a], root) && in_subtree(m, m->geom_bodyid[b], root) &&
            m->geom_bodyid[a] != m->geom_bodyid[b] && can_touch(m, a, b)) {
          // Only the two fingers' pads may meet, and their bodies exclude each other.
          EXPECT_EQ(m->geom_group[a], 0) << robot_name(robot) << " geoms " << a << " " << b;
          EXPECT_EQ(m->geom_group[b], 0) << robot_name(robot) << " geoms " << a << " " << b;
        }
      }
    }
  }
}

TEST(WorldProfile, FingersStartClosedInGymAndOpenInThePaperWorld) {
  for (Robot robot : kAllRobots) {
    PickPlaceEnv paper(load(WorldProfile::kPaper, robot));
    PickPlaceEnv gym(load(WorldProfile::kGym, robot));
    paper.reset(3);
    gym.reset(3);
    const double open_gap = 2 * paper.world().finger_range_m();
    EXPECT_GT(paper.task_state().finger_gap_m, 0.9 * open_gap) << robot_name(robot);
    EXPECT_LT(gym.task_state().finger_gap_m, 0.005) << robot_name(robot);
  }
}

TEST(WorldProfile, TheGripperStartsLowerInGym) {
  for (Robot robot : kAllRobots) {
    PickPlaceEnv paper(load(WorldProfile::kPaper, robot));
    PickPlaceEnv gym(load(WorldProfile::kGym, robot));
    paper.reset(5);
    gym.reset(5);
    EXPECT_NEAR(paper.task_state().gripper.z() - layout::kTableTop_z,
                world_parameters(WorldProfile::kPaper).gripper_start_above_table_m, 0.01);
    EXPECT_NEAR(gym.task_state().gripper.z() - layout::kTableTop_z,
                world_parameters(WorldProfile::kGym).gripper_start_above_table_m, 0.01);
  }
}

Eigen::Vector3d mocap_target(const PickPlaceEnv& env) {
  const double* p = env.mj_data()->mocap_pos + 3 * env.world().ids().gripper_mocap;
  return {p[0], p[1], p[2]};
}

Eigen::Vector3d grip_site(const PickPlaceEnv& env) {
  const double* p = env.mj_data()->site_xpos + 3 * env.world().ids().grip_site;
  return {p[0], p[1], p[2]};
}

// Gym resets the target to the gripper before adding the action; the paper world adds
// the action to the previous target and keeps it in the workspace box.
TEST(WorldProfile, GymMovesTheTargetFromTheGripperThePaperWorldAccumulatesIt) {
  const Eigen::Vector3d goal(1.3, 0.75, 0.45);
  const Action push{1.0, -0.5, 0.25, 0.0};
  const Eigen::Vector3d delta = layout::kActionPositionScale * push.head<3>();
  PickPlaceEnv gym(load(WorldProfile::kGym));
  gym.reset(7);
  for (int step = 0; step < 3; ++step) {
    const Eigen::Vector3d before = grip_site(gym);
    gym.step(push, goal, Objective::kTask);
    EXPECT_LT((mocap_target(gym) - (before + delta)).norm(), 1e-12) << "step " << step;
  }
  PickPlaceEnv paper(load(WorldProfile::kPaper));
  paper.reset(7);
  for (int step = 0; step < 3; ++step) {
    const Eigen::Vector3d before = mocap_target(paper);
    paper.step(push, goal, Objective::kTask);
    const Eigen::Vector3d expected =
        (before + delta).cwiseMax(layout::kWorkspaceMin).cwiseMin(layout::kWorkspaceMax);
    EXPECT_LT((mocap_target(paper) - expected).norm(), 1e-12) << "step " << step;
  }
}

TEST(WorldProfile, WithNoActionTheGripperHoldsStillInEveryWorld) {
  for (WorldProfile profile : kAllWorldProfiles) {
    for (Robot robot : kAllRobots) {
      PickPlaceEnv env(load(profile, robot));
      env.reset(11);
      const Eigen::Vector3d start = env.task_state().gripper;
      for (int step = 0; step < 10; ++step) {
        env.step(Action{0.0, 0.0, 0.0, 0.0}, start, Objective::kTask);
      }
      EXPECT_LT((env.task_state().gripper - start).norm(), 0.005)
          << world_profile_name(profile) << " " << robot_name(robot);
    }
  }
}

// Gym's finger command is ctrl = q + action in metres; the paper world's scales the
// action by the finger's range.
TEST(WorldProfile, GymCommandsTheFingersInMetres) {
  const Eigen::Vector3d goal(1.3, 0.75, 0.45);
  for (WorldProfile profile : kAllWorldProfiles) {
    PickPlaceEnv env(load(profile));
    env.reset(13);
    env.step(Action{0.0, 0.0, 0.0, 1.0}, goal, Objective::kTask);  // part open
    const WorldIds& ids = env.world().ids();
    const double range = env.world().finger_range_m();
    const double q = env.mj_data()->qpos[ids.finger_qpos[0]];
    constexpr double kAction = -0.1;
    env.step(Action{0.0, 0.0, 0.0, kAction}, goal, Objective::kTask);
    const double scale = profile == WorldProfile::kGym ? 1.0 : range;
    EXPECT_DOUBLE_EQ(env.mj_data()->ctrl[ids.finger_actuator[0]],
                     std::clamp(q + kAction * scale, 0.0, range))
        << world_profile_name(profile);
  }
}

}  // namespace
}  // namespace pnp::sim
