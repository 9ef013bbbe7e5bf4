// The controller's rules over an arm of any kind: what reaches the arm, and when. The arm
// here is a recorder (it moves nowhere), so the rules are pinned apart from any physics;
// robot_controller_service_test plays the same rules over the simulated Panda.

#include "robot/arm_controller.h"

#include <gtest/gtest.h>

#include <chrono>
#include <vector>

#include "common/error.h"

namespace pnp::robot {
namespace {

class RecordingArm final : public ArmBackend {
 public:
  BackendReading reading() const override { return reading_; }
  IntakeOutcome command(const ArmTarget& target) override {
    commands.push_back(target);
    reading_.mode = ArmMode::kTracking;
    reading_.target_base = {target.position_m, target.orientation};
    reading_.commanded_base = reading_.target_base;
    return {};
  }
  double default_max_speed_m_per_s() const override { return 0.5; }
  void stop() override { reading_.mode = ArmMode::kStopped; }
  void resume() override { reading_.mode = ArmMode::kHolding; }
  void after_target() override { ++answered; }

  std::vector<ArmTarget> commands;
  int answered = 0;

 private:
  BackendReading reading_ = [] {
    BackendReading r;
    r.tcp_base =
        r.commanded_base = {Eigen::Vector3d(0.4, 0.0, 0.2), Eigen::Quaterniond::Identity()};
    return r;
  }();
};

class ArmControllerTest : public ::testing::Test {
 protected:
  TargetRequest target(std::uint64_t sequence, Eigen::Vector3d position) const {
    TargetRequest t;
    t.sequence = sequence;
    t.frame_id = "panda_link0";
    t.position_m = position;
    t.gripper_width_m = 0.04;
    t.stamp = std::chrono::system_clock::now();
    return t;
  }

  RecordingArm arm_;
  ArmController controller_{arm_, {}};
};

TEST_F(ArmControllerTest, OnlyTargetsWithinTheControllersOwnLimitsReachTheArm) {
  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  // Below the table, then a 30 cm jump, then a fine step: only the last reaches the arm.
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(1, {0.4, 0.0, -0.05})).status,
            ControllerStatus::kOutsideLimits);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(2, {0.4, 0.3, 0.2})).status,
            ControllerStatus::kOutsideLimits);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(3, {0.42, 0.0, 0.2})).status,
            ControllerStatus::kOk);
  ASSERT_EQ(arm_.commands.size(), 1u);
  EXPECT_DOUBLE_EQ(arm_.commands[0].position_m.x(), 0.42);
  // A target asking for no speed gets the arm's default; every answer lets time pass.
  EXPECT_DOUBLE_EQ(arm_.commands[0].max_speed_m_per_s, 0.5);
  EXPECT_EQ(arm_.answered, 3);
}

TEST_F(ArmControllerTest, StaleUnstampedOrOutOfOrderTargetsNeverReachTheArm) {
  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  auto old = target(1, {0.41, 0.0, 0.2});
  old.stamp = std::chrono::system_clock::now() - std::chrono::seconds(2);
  EXPECT_EQ(controller_.take_target(lease.id, stream, old).status, ControllerStatus::kStale);
  auto unstamped = target(2, {0.41, 0.0, 0.2});
  unstamped.stamp.reset();
  EXPECT_EQ(controller_.take_target(lease.id, stream, unstamped).status, ControllerStatus::kStale);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(5, {0.41, 0.0, 0.2})).status,
            ControllerStatus::kOk);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(4, {0.42, 0.0, 0.2})).status,
            ControllerStatus::kInvalidTarget);
  EXPECT_EQ(arm_.commands.size(), 1u);
}

TEST_F(ArmControllerTest, AnEmergencyStopIsClearedOnlyByAnOperatorRepeatingItsReason) {
  const auto lease = controller_.acquire_lease("test", 0);
  const auto stream = controller_.open_stream(lease.id);
  controller_.stop("person in the cell", StopKind::kEmergency);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(1, {0.41, 0.0, 0.2})).status,
            ControllerStatus::kStopped);
  EXPECT_TRUE(arm_.commands.empty());
  // The lease holder cannot clear it, nor an operator who does not repeat the reason.
  EXPECT_THROW(controller_.resume({lease.id, "", ""}), Error);
  EXPECT_THROW(controller_.resume({"", "cell clear", "ops"}), Error);
  EXPECT_EQ(controller_.state().arm.mode, ArmMode::kStopped);
  const auto cleared = controller_.resume({"", "person in the cell", "ops"});
  EXPECT_EQ(cleared.kind, StopKind::kEmergency);
  EXPECT_EQ(controller_.take_target(lease.id, stream, target(2, {0.41, 0.0, 0.2})).status,
            ControllerStatus::kOk);
}

TEST_F(ArmControllerTest, ASupersededStreamOrAnotherClientsLeaseMovesNothing) {
  const auto lease = controller_.acquire_lease("first", 0);
  const auto old_stream = controller_.open_stream(lease.id);
  const auto new_stream = controller_.open_stream(lease.id);
  EXPECT_EQ(controller_.take_target(lease.id, old_stream, target(1, {0.41, 0.0, 0.2})).status,
            ControllerStatus::kLeaseLost);
  EXPECT_THROW(controller_.acquire_lease("second", 0), Error);
  EXPECT_EQ(controller_.take_target("forged", new_stream, target(1, {0.41, 0.0, 0.2})).status,
            ControllerStatus::kLeaseLost);
  EXPECT_TRUE(arm_.commands.empty());
}

}  // namespace
}  // namespace pnp::robot
