#pragma once
// The fault-injection run behind pnp-bench-faults: the robot gateway drives the simulated
// Panda (real-time clock) with the served hierarchy for N episodes, one planned fault per
// episode (fault_plan.h), through fault-injecting proxies in front of the controller and
// the inference service, all on loopback in this process, exactly the code
// pnp-robot-gateway, pnp-robot-sim and pnp-inference-server run. An ArmMonitor watches the
// arm at its 1 kHz tick. After an emergency stop the run does what an operator does: it
// reads the stop's reason and clears it acknowledging that reason, then goes on.
//
// What it measures (the acceptance of every fault): no target outside the controller's
// box was ever taken in; after every fault the arm was holding or stopped, with nothing
// new taken in, within the gateway's dead-man time; the run completed its episodes.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "robot/gateway_config.h"

namespace pnp::faults {

struct FaultRunSpec {
  int episodes = 100;
  std::uint64_t seed = 7000;             // the fault plan's seed; episode k plays scene seed + k
  std::filesystem::path checkpoints;     // a Panda block hierarchy: {approach,...,hlc}.ckpt
  robot::GatewayConfig config;           // the gateway's (a miscalibrated copy is derived)
  std::chrono::milliseconds stall{300};  // how long a stalled controller or inference waits
  int max_call = 12;                     // faults fire on calls 1..max_call of their kind
  std::filesystem::path work_dir;        // the inference service's store
};

// The planned gateway config with its table 3 cm too low (and its box floor with it),
// valid as a config: what a typo'd calibration gives. Only the controller's own limits
// then keep the pads off the real table.
robot::GatewayConfig miscalibrated(const robot::GatewayConfig& config);

// One JSON object: the gateway's summary over every episode, and per fault kind the
// planned and fired counts, how the episodes ended, how the arm was left, the hold and end
// latencies after the fault, plus the run's verdicts (executed_outside_controller_box,
// faults_not_held_within_deadman, episodes_completed).
nlohmann::json run_faults(const FaultRunSpec& spec);

}  // namespace pnp::faults
