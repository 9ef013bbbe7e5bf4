// The fault-injection run's parts: the seeded plan, the switch the proxies fire, and a
// short real-time run with every kind of fault fired early, whose verdicts must hold.

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

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
