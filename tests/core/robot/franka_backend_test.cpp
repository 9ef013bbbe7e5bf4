// The Franka backend behind the controller's rules, fed FrankaState samples as
// franka_state_controller publishes them, its requests to franka_ros recorded: frames,
// the latching of the arm's own faults and their clearing by an operator, freshness of
// the state and of the tracker, the hand.

#include <gtest/gtest.h>

#include <atomic>
#include <numbers>
#include <thread>
#include <vector>

#include "common/error.h"
#include "robot/franka_controller.h"

namespace pnp::robot {
namespace {

using std::chrono::milliseconds;

struct Recorder final : FrankaCommands {
  void send_equilibrium_pose(const geometry::Pose& ee_base) override {
    equilibria.push_back(ee_base);
  }
  void send_gripper_move(double width_m, double) override { moves.push_back(width_m); }
  void send_gripper_grasp(double width_m, double inner, double outer, double,
                          double force_n) override {
    grasps.push_back(width_m);
    EXPECT_LE(width_m - inner, 1e-12);  // any object narrower than the opening is held
    EXPECT_GE(width_m + outer, 0.08 - 1e-12);
    EXPECT_DOUBLE_EQ(force_n, 70);
  }
  void send_error_recovery() override { ++recoveries; }

  std::vector<geometry::Pose> equilibria;
  std::vector<double> moves, grasps;
  int recoveries = 0;
};

Eigen::Matrix4d matrix(const Eigen::Vector3d& t, double yaw) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  m.topRightCorner<3, 1>() = t;
  return m;
}

Eigen::Matrix4d pointing_down(const Eigen::Vector3d& t) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() =
      Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).toRotationMatrix();
  m.topRightCorner<3, 1>() = t;
  return m;
}

std::array<double, 16> column_major(const Eigen::Matrix4d& m) {
  std::array<double, 16> out{};
  Eigen::Map<Eigen::Matrix4d>(out.data()) = m;
  return out;
}

// A Franka Hand's default end effector: 0.1034 m down the flange, turned -45 degrees.
const Eigen::Matrix4d kFlangeFromEe = matrix({0, 0, 0.1034}, -std::numbers::pi / 4);

class FrankaBackendTest : public ::testing::Test {
 protected:
  FrankaStateSample sample(const Eigen::Matrix4d& base_from_flange, std::uint8_t mode = 2,
                           std::vector<std::string> errors = {}) {
    FrankaStateSample s;
    s.received = now_;
    s.O_T_EE = column_major(base_from_flange * kFlangeFromEe);
    s.F_T_EE = column_major(kFlangeFromEe);
    s.robot_mode = mode;
    s.current_errors = std::move(errors);
    return s;
  }
  // The bridge's loop: a state every tick, then the tick, for `ms` milliseconds.
  void run(int ms, std::uint8_t mode = 2, std::vector<std::string> errors = {}) {
    for (int k = 0; k < ms; ++k) {
      now_ += milliseconds(1);
      arm_.on_state(sample(flange_, mode, errors));
      arm_.tick(now_, 0.001);
    }
  }
  TargetRequest target(std::uint64_t sequence, const Eigen::Vector3d& grip, double width) const {
    TargetRequest t;
    t.sequence = sequence;
    t.frame_id = "panda_link0";
    t.position_m = grip;
    t.orientation = Eigen::Quaterniond(pointing_down(grip).topLeftCorner<3, 3>());
    t.gripper_width_m = width;
    t.stamp = std::chrono::system_clock::now();
    return t;
  }

  SteadyTime now_{std::chrono::seconds(100)};
  Eigen::Matrix4d flange_ = pointing_down({0.4, 0.0, 0.3});
  Recorder ros_;
  FrankaController arm_{ros_, {}, {}};
  ArmController& controller_ = arm_;
};

TEST_F(FrankaBackendTest, ThePoseItReportsAndCommandsIsTheGripPointWhateverTheEndEffectorFrame) {
  run(1);
  const BackendReading r = controller_.state().arm;
  // The grip point 0.0934 m down the flange's z axis: pointing down, 0.0934 m below it.
  EXPECT_TRUE(r.tcp_base.position_m.isApprox(Eigen::Vector3d(0.4, 0.0, 0.3 - 0.0934), 1e-12));
  // Holding: the first equilibrium pose is the measured end effector, no jump.
  ASSERT_FALSE(ros_.equilibria.empty());
  const Eigen::Matrix4d ee = flange_ * kFlangeFromEe;
  EXPECT_TRUE(ros_.equilibria.back().position_m.isApprox(ee.topRightCorner<3, 1>(), 1e-12));

  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  const Eigen::Vector3d goal(0.43, 0.02, 0.2);
  ASSERT_EQ(controller_.take_target(lease.id, stream, target(1, goal, 0.08)).status,
            ControllerStatus::kOk);
  run(600);
  // The equilibrium is the end effector that puts the grip point on the target.
  const Eigen::Matrix4d wanted_ee =
      pointing_down(goal) * matrix({0, 0, -0.0934}, 0) * kFlangeFromEe;
  EXPECT_TRUE(ros_.equilibria.back().position_m.isApprox(wanted_ee.topRightCorner<3, 1>(), 1e-9));
  EXPECT_LT(ros_.equilibria.back().orientation.angularDistance(
                Eigen::Quaterniond(wanted_ee.topLeftCorner<3, 3>())),
            1e-9);
}

TEST_F(FrankaBackendTest, AReflexHoldsTheArmUntilAnOperatorAcknowledgesItThenRecoveryIsSent) {
  run(1);
  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  run(1, 4, {"cartesian_reflex", "joint_velocity_violation"});
  const ControllerReport state = controller_.state();
  EXPECT_EQ(state.arm.mode, ArmMode::kStopped);
  EXPECT_EQ(state.stop_kind, StopKind::kEmergency);
  EXPECT_NE(state.stop_reason.find("reflex"), std::string::npos) << state.stop_reason;
  EXPECT_NE(state.stop_reason.find("cartesian_reflex, joint_velocity_violation"),
            std::string::npos);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(1, {0.41, 0, 0.2}, 0.08)).status,
            ControllerStatus::kStopped);
  // Not by the lease holder, not without the reason: no recovery is sent.
  EXPECT_THROW(controller_.resume({lease.id, "", ""}), Error);
  EXPECT_THROW(controller_.resume({"", "reflex", "ops"}), Error);
  EXPECT_EQ(ros_.recoveries, 0);
  controller_.resume({"", state.stop_reason, "ops"});
  EXPECT_EQ(ros_.recoveries, 1);
  run(5);  // franka_control cleared it: mode move, no errors
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(2, {0.41, 0, 0.2}, 0.08)).status,
            ControllerStatus::kOk);
}

TEST_F(FrankaBackendTest, RecoveryThatDoesNotClearTheArmStopsItAgain) {
  run(1, 4, {"joint_reflex"});
  controller_.resume({"", controller_.state().stop_reason, "ops"});
  run(5100, 4, {"joint_reflex"});
  const ControllerReport state = controller_.state();
  EXPECT_EQ(state.stop_kind, StopKind::kEmergency);
  EXPECT_NE(state.stop_reason.find("error recovery did not clear"), std::string::npos)
      << state.stop_reason;
}

TEST_F(FrankaBackendTest, AStalledStateTopicStopsTheArmNamingTheStall) {
  run(10);
  now_ += milliseconds(150);  // no state for 150 ms
  arm_.tick(now_, 0.001);
  controller_.stop("operator", StopKind::kProtective);  // a stop never weakens the latched one
  const ControllerReport state = controller_.state();
  EXPECT_EQ(state.stop_kind, StopKind::kEmergency);
  EXPECT_NE(state.stop_reason.find("stalled"), std::string::npos) << state.stop_reason;
}

TEST_F(FrankaBackendTest, TheTrackersPoseIsReportedOnlyWhileFresh) {
  run(1);
  arm_.on_object({now_, {Eigen::Vector3d(0.5, 0.1, 0.02), Eigen::Quaterniond::Identity()}});
  run(100);
  ASSERT_TRUE(controller_.state().arm.object_base.has_value());
  EXPECT_DOUBLE_EQ(controller_.state().arm.object_base->position_m.x(), 0.5);
  run(150);  // 250 ms old: more than object_timeout_s
  EXPECT_FALSE(controller_.state().arm.object_base.has_value());
}

// A tracker publishes at its own rate: the pose it sent before a scene reset may still be
// the latest when the arm's first state after it arrives. The reset waits for the
// tracker's first pose after it, so the scene before is never read as the scene after.
TEST_F(FrankaBackendTest, ASceneResetWaitsForTheTrackersFirstPoseAfterIt) {
  using Clock = std::chrono::steady_clock;
  const auto feed = [&](const std::stop_token& stop, const std::atomic<bool>& reset_done) {
    int after_reset = 0;
    while (!stop.stop_requested()) {
      std::this_thread::sleep_for(milliseconds(2));
      FrankaStateSample s = sample(flange_);
      s.received = Clock::now();
      arm_.on_state(s);
      arm_.tick(s.received, 0.002);
      // The tracker's first pose after the reset comes 20 states after the arm's first.
      if (reset_done.load() && ++after_reset == 20) {
        arm_.on_object({Clock::now(), {Eigen::Vector3d(0.3, -0.1, 0.02), {1, 0, 0, 0}}});
      }
    }
  };
  std::atomic<bool> reset_done{false};
  arm_.on_object({Clock::now(), {Eigen::Vector3d(0.5, 0.1, 0.02), {1, 0, 0, 0}}});
  std::jthread ros(feed, std::cref(reset_done));
  const auto lease = controller_.acquire_lease("test", 0);
  const auto [seed, report] = arm_.reset_scene(lease.id, [&] {
    reset_done.store(true);
    return 7;
  });
  EXPECT_EQ(seed, 7);
  ASSERT_TRUE(report.arm.object_base.has_value());
  EXPECT_DOUBLE_EQ(report.arm.object_base->position_m.x(), 0.3);
}

TEST_F(FrankaBackendTest, TheHandGetsOneGoalPerOpeningOrClosingNotOnePerStep) {
  run(1);
  arm_.on_gripper_width(0.08);
  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  std::uint64_t seq = 0;
  for (const double width : {0.08, 0.079, 0.0, 0.001, 0.0, 0.08, 0.078}) {
    ASSERT_EQ(controller_.take_target(lease.id, stream, target(++seq, {0.4, 0, 0.2}, width)).status,
              ControllerStatus::kOk);
  }
  EXPECT_EQ(ros_.moves, (std::vector<double>{0.08, 0.08}));
  EXPECT_EQ(ros_.grasps, (std::vector<double>{0.0}));
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(++seq, {0.4, 0, 0.2}, 0.2)).status,
            ControllerStatus::kInvalidTarget);
}

TEST_F(FrankaBackendTest, NothingMovesBeforeTheArmHasSaidWhereItIs) {
  arm_.tick(now_, 0.001);
  EXPECT_TRUE(ros_.equilibria.empty());
  EXPECT_EQ(controller_.state().arm.mode, ArmMode::kFault);
  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(1, {0.4, 0, 0.2}, 0.08)).status,
            ControllerStatus::kStopped);
}

}  // namespace
}  // namespace pnp::robot
