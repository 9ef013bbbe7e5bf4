#pragma once
// What the fault-injecting proxies share with the benchmark: the fault armed for the
// running episode, the counts of the calls it may fire on, and when it fired.
// Thread-safe: gRPC handler threads call fire(), the benchmark arms and reads.

#include <chrono>
#include <mutex>
#include <optional>

#include "bench/faults/fault_plan.h"

namespace pnp::faults {

// The calls a fault is counted on.
enum class CallSite { kGetState, kPredict, kTarget };
// Where `kind` is counted; nullopt for a fault of the whole episode.
std::optional<CallSite> call_site(FaultKind kind);

class FaultSwitch {
 public:
  using Clock = std::chrono::steady_clock;

  // Arms `fault` for the next episode (nullopt: none) and zeroes the counts.
  void arm(std::optional<PlannedFault> fault);
  // Counts one call at `site`; the armed fault's kind exactly once, on the call it fires
  // on (recording the time), when that kind is counted at `site`.
  std::optional<FaultKind> fire(CallSite site);
  std::optional<Clock::time_point> fired_at() const;

  // A policy that drives down into the table (every answer's dz = -1) while set.
  void set_policy_dives(bool dives);
  bool policy_dives() const;

  // A stalled controller: every call waits until then.
  void stall_controller_until(Clock::time_point until);
  Clock::time_point controller_stalled_until() const;

 private:
  mutable std::mutex mutex_;
  std::optional<PlannedFault> armed_;       // guarded by mutex_
  int counts_[3] = {0, 0, 0};               // guarded by mutex_
  std::optional<Clock::time_point> fired_;  // guarded by mutex_
  Clock::time_point stalled_until_{};       // guarded by mutex_
  bool policy_dives_ = false;               // guarded by mutex_
};

}  // namespace pnp::faults
