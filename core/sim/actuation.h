#pragma once
// How an environment's hand follows the policy's actions.
//
//   mocap  gym's control: the hand is welded to a mocap target that the action moves by
//          up to 5 cm a step; the hand reaches it within one 40 ms step, whatever an arm
//          could do. FetchPickAndPlace's, so the Fetch world keeps it (gym is the
//          benchmark).
//   arm    the real arm's control: each action becomes a Cartesian target planned as the
//          robot gateway plans it and tracked by the simulated Panda controller (IK and a
//          1 kHz joint-space loop within the datasheet's velocity, acceleration and jerk
//          limits: arm_sim/simulated_arm.h), the same code pnp-robot-sim runs. The hand
//          lags behind a 5 cm command as a real Panda does. The Panda only.
//
// Recorded with every run and checkpoint beside the world profile; the served policy's
// actuation is shown by the inference service and checked by pnpctl evaluate and the
// gateway.

#include <array>
#include <string_view>

#include "sim/robot.h"

namespace pnp::sim {

enum class Actuation { kMocap, kArm };

inline constexpr std::array<Actuation, 2> kAllActuations{Actuation::kMocap, Actuation::kArm};

std::string_view actuation_name(Actuation actuation);

// Parses "mocap" or "arm"; anything else is an INVALID_ARGUMENT naming `field`.
Actuation parse_actuation(std::string_view name, std::string_view field = "actuation");

// What a robot is trained and evaluated with unless told otherwise: mocap for both today
// (the Panda's becomes arm once an arm-trained hierarchy holds its results: docs/RESULTS.md).
Actuation default_actuation(Robot robot);

// The steps of an episode with this actuation: gym's 50 for the mocap hand, the arm's 75
// (sim/world_layout.h: a hand that accelerates within the Panda's limits needs longer).
int episode_steps(Actuation actuation);

// INVALID_ARGUMENT naming `field` when `robot` cannot be driven with `actuation` (only
// the Panda has an arm controller).
void require_supported(Robot robot, Actuation actuation, std::string_view field = "actuation");

}  // namespace pnp::sim
