#pragma once
// The Panda's grip point (its tool centre point, TCP): the point every pose target and
// every measured gripper pose names. One definition for the simulated worlds (site "grip"
// in sim/mjcf/panda.xml, pinned by a test), the robot gateway and the controller stand-in.
// A real Franka Hand's default end-effector frame is 0.1034 m from the flange (the
// fingertips); a controller must be set to this TCP instead, and the gateway refuses to
// drive one that reports another (GetStateResponse.tcp_from_flange_m).

namespace pnp::sim {

// Along the flange's z axis, from panda_link8 (the flange) to the grip point.
inline constexpr double kGripPointFromFlange_m = 0.0934;
// The finger pads reach this far past the grip point (their tips at 0.1035 m).
inline constexpr double kPadReachBelowGripPoint_m = 0.0101;
// What a target keeps between the pads and the table when the hand points down.
inline constexpr double kPadClearance_m = 0.002;
// Two TCP definitions closer than this are the same point.
inline constexpr double kTcpTolerance_m = 1e-4;

// The lowest grip-point height a target may have above a table top at `table_top_z_m`
// with the hand pointing down (the policy's only orientation).
constexpr double lowest_grip_point_z(double table_top_z_m) {
  return table_top_z_m + kPadReachBelowGripPoint_m + kPadClearance_m;
}

}  // namespace pnp::sim
