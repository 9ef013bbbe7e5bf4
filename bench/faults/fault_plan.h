#pragma once
// The faults pnp-bench-faults injects, one per episode, and their seeded schedule. Each
// is something that happens to a real cell: a controller or an inference server that
// stops answering for a while, a reading the controller should never send, a network
// that drops the drive stream, a person pressing the E-stop, and a gateway whose table
// is configured 3 cm too low while the policy drives down into it (only the controller's
// own limits are left to keep the pads off the table).

#include <cstdint>
#include <string_view>
#include <vector>

namespace pnp::faults {

enum class FaultKind {
  kControllerStall,       // every controller call waits stall_ms (GetState first)
  kInferenceStall,        // one PredictSession answer arrives stall_ms late
  kBrokenReading,         // one GetState answer with a NaN, a zero quaternion or no object
  kDroppedStream,         // the drive stream breaks on a target (the target is lost)
  kEmergencyStop,         // someone in the cell stops the arm (an operator clears it)
  kMiscalibratedGateway,  // the whole episode: the gateway's table 3 cm low, the policy diving
};
inline constexpr int kFaultKinds = 6;
std::string_view fault_kind_name(FaultKind kind);

struct PlannedFault {
  FaultKind kind = FaultKind::kControllerStall;
  // The 1-based count of the call it fires on, among the episode's calls of its kind
  // (GetState for stalls and readings, PredictSession requests, targets).
  int at_call = 1;
};

// One fault per episode: every kind once in each block of kFaultKinds episodes, in a
// seeded order, each at a seeded call in [1, max_call].
std::vector<PlannedFault> plan_faults(int episodes, std::uint64_t seed, int max_call);

}  // namespace pnp::faults
