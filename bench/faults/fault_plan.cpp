#include "bench/faults/fault_plan.h"

#include <array>
#include <numeric>

#include "common/error.h"
#include "common/rng.h"

namespace pnp::faults {

std::string_view fault_kind_name(FaultKind kind) {
  switch (kind) {
    case FaultKind::kControllerStall:
      return "controller_stall";
    case FaultKind::kInferenceStall:
      return "inference_stall";
    case FaultKind::kBrokenReading:
      return "broken_reading";
    case FaultKind::kDroppedStream:
      return "dropped_stream";
    case FaultKind::kEmergencyStop:
      return "emergency_stop";
    case FaultKind::kMiscalibratedGateway:
      return "miscalibrated_gateway";
  }
  return "unknown";
}

std::vector<PlannedFault> plan_faults(int episodes, std::uint64_t seed, int max_call) {
  if (episodes < 0) throw_invalid_argument("episodes", "a count >= 0", std::to_string(episodes));
  if (max_call < 1) throw_invalid_argument("max_call", "a count >= 1", std::to_string(max_call));
  Rng rng(seed);
  std::vector<PlannedFault> plan;
  plan.reserve(static_cast<std::size_t>(episodes));
  std::array<int, kFaultKinds> order{};
  while (std::ssize(plan) < episodes) {
    std::iota(order.begin(), order.end(), 0);
    for (std::size_t i = order.size() - 1; i > 0; --i) {  // Fisher-Yates, Rng's draws
      std::swap(order[i], order[rng.below(i + 1)]);
    }
    for (int k : order) {
      if (std::ssize(plan) == episodes) break;
      plan.push_back({static_cast<FaultKind>(k),
                      1 + static_cast<int>(rng.below(static_cast<std::uint64_t>(max_call)))});
    }
  }
  return plan;
}

}  // namespace pnp::faults
