#pragma once
// The record of a run's targets (pnp-robot-gateway --record FILE): one JSON line per
// target sent to the arm or, in a dry run, to its shadow, in the arm's base frame:
//   {"seed":3000,"step":12,"position_base_m":[x,y,z],"orientation_base_wxyz":[w,x,y,z],
//    "gripper_width_m":0.08}
// Doubles are written so they read back exactly, so a dry run's record and the live
// run's can be compared number for number.

#include <cstdint>
#include <fstream>
#include <string>

#include "robot/safety_limits.h"

namespace pnp::gateway {

class TargetRecord {
 public:
  // UNAVAILABLE naming `path` if it cannot be opened for writing (truncated).
  explicit TargetRecord(const std::string& path);
  // UNAVAILABLE if the line cannot be written.
  void add(std::uint64_t seed, int step, const robot::PoseTarget& target);

 private:
  std::string path_;
  std::ofstream file_;
};

}  // namespace pnp::gateway
