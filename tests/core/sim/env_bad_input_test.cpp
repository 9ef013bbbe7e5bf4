// Every bad input is refused with an error naming the field, before the physics is
// touched: a refused call leaves the environment exactly as it was.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "common/error.h"
#include "sim/pick_place_env.h"
#include "sim/vec_env.h"
#include "test_worlds.h"

namespace pnp::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Snapshot {
  std::vector<double> qpos, qvel, mocap;
  int steps;
  explicit Snapshot(const PickPlaceEnv& env)
      : qpos(env.mj_data()->qpos, env.mj_data()->qpos + env.mj_model()->nq),
        qvel(env.mj_data()->qvel, env.mj_data()->qvel + env.mj_model()->nv),
        mocap(env.mj_data()->mocap_pos, env.mj_data()->mocap_pos + 3 * env.mj_model()->nmocap),
        steps(env.elapsed_steps()) {}
  bool operator==(const Snapshot&) const = default;
};

void expect_refused(PickPlaceEnv& env, std::vector<double> action, std::vector<double> goal,
                    ErrorCode code, const std::string& message) {
  const Snapshot before(env);
  try {
    env.step(action, goal, Objective::kApproach);
    ADD_FAILURE() << "accepted: expected " << message;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code);
    EXPECT_EQ(std::string(e.what()), message);
  }
  EXPECT_TRUE(Snapshot(env) == before) << "a refused step changed the state";
}

class EnvBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    env_.reset(1);
    env_.step(std::vector<double>{0.3, 0, 0, 1}, std::vector<double>{1.3, 0.7, 0.5},
              Objective::kApproach);
  }
  PickPlaceEnv env_{testing::world()};
  const std::vector<double> good_goal_{1.3, 0.7, 0.5};
  const std::vector<double> good_action_{0, 0, 0, 1};
};

TEST_F(EnvBadInput, NaNAction) {
  expect_refused(env_, {0, kNaN, 0, 1}, good_goal_, ErrorCode::kInvalidArgument,
                 "action[1]: expected a finite number, got nan");
}

TEST_F(EnvBadInput, InfiniteAction) {
  expect_refused(env_, {0, 0, 0, -kInf}, good_goal_, ErrorCode::kInvalidArgument,
                 "action[3]: expected a finite number, got -inf");
}

TEST_F(EnvBadInput, WrongSizedAction) {
  expect_refused(env_, {0, 0, 0}, good_goal_, ErrorCode::kInvalidArgument,
                 "action: expected 4 values, got 3");
  expect_refused(env_, {0, 0, 0, 0, 0}, good_goal_, ErrorCode::kInvalidArgument,
                 "action: expected 4 values, got 5");
}

TEST_F(EnvBadInput, NaNOrWrongSizedGoal) {
  expect_refused(env_, good_action_, {1, kNaN, 0}, ErrorCode::kInvalidArgument,
                 "goal[1]: expected a finite number, got nan");
  expect_refused(env_, good_action_, {1, 2}, ErrorCode::kInvalidArgument,
                 "goal: expected 3 values, got 2");
}

TEST_F(EnvBadInput, OutOfRangeActionIsClippedNotRefused) {
  const StepResult r =
      env_.step(std::vector<double>{50, 0, 0, 1}, good_goal_, Objective::kApproach);
  EXPECT_EQ(r.fault, PhysicsFault::kNone);
  EXPECT_EQ(env_.elapsed_steps(), 2);
}

TEST(EnvState, StepBeforeResetIsAFailedPrecondition) {
  PickPlaceEnv env(testing::world());
  expect_refused(env, {0, 0, 0, 1}, {1, 1, 1}, ErrorCode::kFailedPrecondition,
                 "step: no episode has started; call reset() first");
}

TEST(EnvState, TheFiftyStepLimitIsEnforced) {
  PickPlaceEnv env(testing::world());
  env.reset(2);
  StepResult r;
  for (int t = 0; t < 50; ++t) {
    ASSERT_FALSE(r.episode_over);
    r = env.step(std::vector<double>{0, 0, 0, 1}, std::vector<double>{1, 1, 1}, Objective::kTask);
  }
  EXPECT_TRUE(r.episode_over);
  EXPECT_TRUE(env.needs_reset());
  expect_refused(env, {0, 0, 0, 1}, {1, 1, 1}, ErrorCode::kFailedPrecondition,
                 "step: the episode ended after 50 steps; call reset()");
  env.reset(3);
  EXPECT_NO_THROW(
      env.step(std::vector<double>{0, 0, 0, 1}, std::vector<double>{1, 1, 1}, Objective::kTask));
}

TEST(Names, UnknownRobotOrObjectIsRefusedNamingTheField) {
  try {
    parse_robot("ur5");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "robot: expected one of fetch, panda, got \"ur5\"");
  }
  try {
    parse_object("sphere", "--object");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "--object: expected one of block, small_block, cylinder, got \"sphere\"");
  }
}

TEST(VecEnvInput, NonPositiveEnvCountIsRefused) {
  for (long long n : {0LL, -4LL}) {
    try {
      VecEnv vec(testing::world(), n, 1);
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_EQ(std::string(e.what()),
                "num_envs: expected a positive integer, got " + std::to_string(n));
    }
  }
}

TEST(VecEnvInput, OneBadActionRefusesTheWholeBatchAndStepsNothing) {
  VecEnv vec(testing::world(), 3, 2);
  vec.reset(8);
  std::vector<double> actions(12, 0.0), goals(9, 0.5);
  actions[2 * 4 + 1] = kNaN;  // env 2, action[1]
  std::vector<Objective> objectives(3, Objective::kApproach);
  std::vector<StepResult> results(3);
  try {
    vec.step(actions, goals, objectives, results);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "actions[9]: expected a finite number, got nan");
  }
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(vec.env(i).elapsed_steps(), 0);
  std::vector<Objective> short_objectives(2, Objective::kApproach);
  EXPECT_THROW(vec.step(std::vector<double>(12, 0.0), goals, short_objectives, results), Error);
  std::vector<Objective> bogus(3, static_cast<Objective>(7));
  EXPECT_THROW(vec.step(std::vector<double>(12, 0.0), goals, bogus, results), Error);
}

}  // namespace
}  // namespace pnp::sim
