#pragma once
// The policy's 25-value observation rebuilt from what a real arm reports (the gripper's
// measured position and finger gap, the object's pose from perception), all already in
// the simulation's frame. The simulation reads velocities from the physics; here they are
// the change since the previous cycle, which at the policy's period (the simulation's
// 40 ms step) is what "velocity x dt" measures. The first cycle of an episode has zero
// velocities, as a freshly reset environment's observation has.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "sim/observation.h"

namespace pnp::robot {

struct PerceivedState {
  Eigen::Vector3d gripper_m = Eigen::Vector3d::Zero();
  double finger_gap_m = 0;  // distance between the finger pads
  Eigen::Vector3d object_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond object_orientation = Eigen::Quaterniond::Identity();
};

class PerceivedObservation {
 public:
  // INVALID_ARGUMENT for non-finite values or a finger gap below -2 cm (closed on nothing,
  // simulated fingers read up to ~12 mm below zero: kept as it is).
  sim::Observation update(const PerceivedState& state);
  void reset() { previous_.reset(); }  // a new episode: no velocities yet

 private:
  std::optional<PerceivedState> previous_;
};

}  // namespace pnp::robot
