// The fault-injection run's parts: the seeded plan, the switch the proxies fire, and a
// short real-time run with every kind of fault fired early, whose verdicts must hold.

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <thread>

#include "arm_sim/controller_stand_in.h"
#include "bench/faults/arm_monitor.h"
#include "bench/faults/fault_plan.h"
#include "bench/faults/fault_run.h"
#include "bench/faults/fault_switch.h"
#include "common/error.h"
#include "sim/panda_hand.h"

namespace pnp::faults {
namespace {

TEST(FaultPlan, EveryKindOnceInEachBlockAtASeededCall) {
  const auto plan = plan_faults(2 * kFaultKinds + 1, 11, 12);
  ASSERT_EQ(plan.size(), 2u * kFaultKinds + 1);
  for (int block = 0; block < 2; ++block) {
    std::set<FaultKind> kinds;
    for (int i = 0; i < kFaultKinds; ++i)
      kinds.insert(plan[static_cast<std::size_t>(block * kFaultKinds + i)].kind);
    EXPECT_EQ(kinds.size(), static_cast<std::size_t>(kFaultKinds));
  }
  for (const PlannedFault& f : plan) {
    EXPECT_GE(f.at_call, 1);
    EXPECT_LE(f.at_call, 12);
  }
  const auto again = plan_faults(2 * kFaultKinds + 1, 11, 12);
  const auto other = plan_faults(2 * kFaultKinds + 1, 12, 12);
  bool differs = false;
  for (std::size_t i = 0; i < plan.size(); ++i) {
    EXPECT_EQ(plan[i].kind, again[i].kind);
    EXPECT_EQ(plan[i].at_call, again[i].at_call);
    differs = differs || plan[i].kind != other[i].kind || plan[i].at_call != other[i].at_call;
  }
  EXPECT_TRUE(differs);
  EXPECT_THROW(plan_faults(3, 1, 0), Error);
}

TEST(FaultSwitch, FiresOnceOnThePlannedCallOfItsSite) {
  FaultSwitch faults;
  faults.arm(PlannedFault{FaultKind::kBrokenReading, 3});
  EXPECT_EQ(faults.fire(CallSite::kTarget), std::nullopt);  // another site's count
  EXPECT_EQ(faults.fire(CallSite::kGetState), std::nullopt);
  EXPECT_EQ(faults.fire(CallSite::kGetState), std::nullopt);
  EXPECT_FALSE(faults.fired_at());
  EXPECT_EQ(faults.fire(CallSite::kGetState), FaultKind::kBrokenReading);
  EXPECT_TRUE(faults.fired_at());
  EXPECT_EQ(faults.fire(CallSite::kGetState), std::nullopt);
  faults.arm(std::nullopt);
  EXPECT_FALSE(faults.fired_at());
  for (int i = 0; i < 5; ++i) EXPECT_EQ(faults.fire(CallSite::kGetState), std::nullopt);
}

// The monitor sees a target the arm took in, judges it against any box, and places it
// after a fault: what the run's verdicts rest on.
TEST(ArmMonitor, RecordsEachTargetTakenInAndJudgesItAgainstABox) {
  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kLockstep;
  arm_sim::ControllerStandIn arm(options);
  ArmMonitor monitor(arm);
  const auto before = ArmMonitor::Clock::now();
  const auto lease = arm.acquire_lease("test", 5);
  const std::uint64_t stream = arm.open_stream(lease.id);
  const geometry::Pose start = arm.state().arm.commanded_base;
  robot::TargetRequest target;
  target.sequence = 1;
  target.frame_id = arm.base_frame_id();
  target.position_m = start.position_m + Eigen::Vector3d(0, 0, -0.02);
  target.orientation = start.orientation;
  target.gripper_width_m = 0.04;
  target.stamp = std::chrono::system_clock::now();
  ASSERT_EQ(arm.take_target(lease.id, stream, target).status, robot::ControllerStatus::kOk);
  for (int i = 0; i < 200 && monitor.targets_taken() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(monitor.targets_taken(), 1);
  EXPECT_EQ(monitor.taken_outside(options.limits.workspace), 0);
  robot::WorkspaceBox above = options.limits.workspace;
  above.min_m.z() = target.position_m.z() + 0.01;  // the target lies below this box
  EXPECT_EQ(monitor.taken_outside(above), 1);
  const auto after = monitor.after_fault(before, ArmMonitor::Clock::now());
  EXPECT_TRUE(after.last_taken.has_value());
  EXPECT_FALSE(
      monitor
          .after_fault(ArmMonitor::Clock::now(), ArmMonitor::Clock::now() + std::chrono::seconds(1))
          .last_taken.has_value());
}

TEST(FaultRun, AMiscalibratedGatewayIsStillAValidConfigWithItsFloorLower) {
  robot::GatewayConfig config =
      robot::GatewayConfig::load(PNP_SOURCE_DIR "/deploy/robot/gateway.json");
  const robot::GatewayConfig wrong = miscalibrated(config);
  EXPECT_NEAR(wrong.limits.table_top_z_m, config.limits.table_top_z_m - 0.03, 1e-12);
  EXPECT_LT(wrong.limits.workspace.min_m.z(), sim::lowest_grip_point_z(0));
}

// Every kind fired within the first calls of its episode, in real time: the arm must be
// holding or stopped within the dead-man time after each, no target outside the
// controller's box taken in, and every episode played (an operator clears the E-stop).
TEST(FaultRun, EveryFaultEndsInAHeldOrStoppedArmAndTheRunCompletes) {
  FaultRunSpec spec;
  spec.episodes = kFaultKinds;
  spec.seed = 7100;
  spec.max_call = 3;
  spec.checkpoints = PNP_SOURCE_DIR "/tests/data/panda_block";
  spec.config = robot::GatewayConfig::load(PNP_SOURCE_DIR "/deploy/robot/gateway.json");
  spec.work_dir = std::filesystem::path(::testing::TempDir()) / "faults_run";
  std::filesystem::remove_all(spec.work_dir);
  const nlohmann::json out = run_faults(spec);
  SCOPED_TRACE(out.dump(2));
  EXPECT_EQ(out["episodes_completed"], kFaultKinds);
  EXPECT_EQ(out["executed_outside_controller_box"], 0);
  EXPECT_EQ(out["faults_not_held_within_deadman"], 0);
  EXPECT_GT(out["targets_taken"].get<int>(), 0);
  const nlohmann::json& f = out["faults"];
  const std::pair<const char*, const char*> expected[] = {{"controller_stall", "deadman"},
                                                          {"inference_stall", "deadman"},
                                                          {"broken_reading", "controller_fault"},
                                                          {"dropped_stream", "controller_fault"},
                                                          {"emergency_stop", "stopped"}};
  for (const auto& [kind, end] : expected) {
    SCOPED_TRACE(kind);
    ASSERT_EQ(f[kind]["fired"], 1);
    EXPECT_EQ(f[kind]["ends"][end], 1);
    EXPECT_LE(f[kind]["held_after_fault_ms"]["max"].get<double>(), out["deadman_ms"]);
  }
  EXPECT_EQ(f["emergency_stop"]["arm_left"]["emergency_stop"], 1);
  EXPECT_EQ(out["operator_clears"], 1);
  EXPECT_EQ(f["miscalibrated_gateway"]["fired"], 1);
  // The gateway let the diving policy's targets below the table through; the controller
  // refused them.
  EXPECT_GT(f["miscalibrated_gateway"]["controller_refusals_by_reason"]
             ["CONTROLLER_STATUS_OUTSIDE_LIMITS"]
                 .get<int>(),
            0);
  std::filesystem::remove_all(spec.work_dir);
}

}  // namespace
}  // namespace pnp::faults
