#pragma once
// One cell of the shape-transfer table: a policy served by the inference service from a
// fresh store, played for N episodes through the robot gateway on the simulated Panda
// controller with one shape on the table (lockstep clock), both services on loopback in
// this process, exactly the code pnp-inference-server, pnp-robot-sim and
// pnp-robot-gateway run. An episode whose controller reading the gateway refuses (it then
// ends the run) counts as a failure with its reason, and the cell goes on with a fresh
// controller from the next seed.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "arm_sim/simulated_arm.h"
#include "bench/shape_transfer/transfer_training.h"
#include "robot/gateway_config.h"
#include "serving/served_policy.h"

namespace pnp::bench {

struct ServedCheckpoints {
  serving::PolicyKind kind = serving::PolicyKind::kHierarchy;
  HierarchyBlobs hierarchy;  // kHierarchy
  training::Blob e2e;        // kEndToEnd (trained on the block)
};

struct GatewayCellSpec {
  sim::ObjectShape shape = sim::ObjectShape::kBlock;
  sim::WorldProfile world = sim::kDefaultWorldProfile;
  const robot::GatewayConfig* config = nullptr;
  int episodes = 200;
  std::uint64_t first_seed = 880000;  // episode k plays scene first_seed + k
  std::filesystem::path work_dir;     // the cell's store, checkpoints and gateway events
  double acceleration_scale = arm_sim::kDefaultAccelerationScale;  // x the Panda's datasheet
};

// The gateway's summary (clients/robot_gateway/gateway_summary.h) plus gateway_errors (episodes
// ended by a refused reading, with their reasons), solved_at_start (successes at step 0: scenes
// that start with the object within the success distance), wall_s, and arm_world: the
// same scenes played by the same served policy in the arm-actuated world (success at the
// episode's end and at any step, and the scenes where the gateway disagrees with the world).
nlohmann::json play_gateway_cell(const GatewayCellSpec& spec, const ServedCheckpoints& served);

}  // namespace pnp::bench
