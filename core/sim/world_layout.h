#pragma once
// The task frame shared by both robots: table, gripper start, sampling regions, control
// scaling and episode timing. Every number here is used by the MJCF generator, the
// samplers, the experts and the tests alike, so each is defined exactly once.

#include <Eigen/Core>

namespace pnp::sim::layout {

// Time: a policy step is 20 physics substeps of 2 ms (40 ms, 25 Hz); 50 steps an episode
// (gym's FetchPickAndPlace), sized for a mocap hand that covers 5 cm a step.
inline constexpr double kPhysicsTimestep_s = 0.002;
inline constexpr int kSubstepsPerStep = 20;
inline constexpr double kStepDuration_s = kPhysicsTimestep_s * kSubstepsPerStep;
inline constexpr int kEpisodeSteps = 50;
// An episode on the arm (the arm-actuated world and the robot gateway): 75 steps, 3 s.
// A Panda within its datasheet limits covers at most about 2.6 cm a step, so 2 s leave
// gym's high goals out of reach: the scripted pipeline completes 0.943 of 300 block
// episodes in 50 steps (every failure a retract still on its way up) and 1.000 in 75
// (docs/SIMULATION.md, "The arm's episode").
inline constexpr int kArmEpisodeSteps = 75;
// The longest episode a client may declare (the gateway's max_episode_steps, a policy
// session's episode_steps): 400 s at 25 Hz, far past any pick and place.
inline constexpr int kMaxEpisodeSteps = 10000;

// Table: a box whose top surface is at kTableTop_z.
inline constexpr double kTableCenter_x = 1.30;
inline constexpr double kTableCenter_y = 0.75;
inline constexpr double kTableHalfX = 0.25;
inline constexpr double kTableHalfY = 0.35;
inline constexpr double kTableTop_z = 0.40;

// The gripper starts pointing down over the centre of the region where objects and goals
// are sampled; in the paper world 0.2 m above the table (kGripperStart), in others at
// their profile's height (world_profile.h, which also holds the sampling ranges).
inline constexpr double kGripperStart_x = 1.34;
inline constexpr double kGripperStart_y = 0.75;
inline constexpr double kPaperGripperStartHeight = 0.20;
inline const Eigen::Vector3d kGripperStart{kGripperStart_x, kGripperStart_y,
                                           kTableTop_z + kPaperGripperStartHeight};

// Control: action xyz in [-1, 1] times this moves the gripper's mocap target per step.
inline constexpr double kActionPositionScale = 0.05;

// In the paper world the mocap target is kept inside this box (world frame, m) so that a
// learner's random exploration can never drag the arm out of its reachable workspace.
inline const Eigen::Vector3d kWorkspaceMin{1.05, 0.40, kTableTop_z + 0.005};
inline const Eigen::Vector3d kWorkspaceMax{1.55, 1.10, kTableTop_z + 0.45};

// Plausibility of the object's motion. The gripper moves at most 1.25 m/s (0.05 m per
// 40 ms), so faster objects, fast spins or an object far from the table mean a contact
// blew up without producing a NaN (measured: an object flung 3.6 m at 200 rad/s, which
// poisoned a critic's training data). Such a step is a physics fault.
inline constexpr double kMaxObjectSpeed_mps = 5.0;
inline constexpr double kMaxObjectSpin_radps = 100.0;
inline constexpr double kMaxObjectDistanceFromTable_m = 1.0;

// Task success: the object's centre within this distance of the episode goal.
inline constexpr double kTaskSuccessDistance = 0.05;

}  // namespace pnp::sim::layout
