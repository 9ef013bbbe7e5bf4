#pragma once
// The robot gateway's settings: where the simulation's frame (the policy's) sits relative
// to the arm's base, the safety limits every target is checked against, and the timing
// the policy was trained with. Read from a JSON file (deploy/robot/gateway.json):
//
//   {"base_from_sim": [[1, 0, 0, -0.88], [0, 1, 0, -0.75], [0, 0, 1, -0.4], [0, 0, 0, 1]],
//    "base_frame_id": "panda_link0",
//    "limits": {"workspace": {"min_m": [x, y, z], "max_m": [x, y, z]}, "table_top_z_m": 0,
//               "max_step_m": 0.1,
//               "max_speed_m_per_s": 1.7, "max_rotation_step_rad": 0.2,
//               "gripper_min_width_m": 0, "gripper_max_width_m": 0.08,
//               "quaternion_norm_tolerance": 0.001},
//    "policy_period_s": 0.04, "deadman_timeout_s": 0.1, "lease_timeout_s": 0.5,
//    "max_episode_steps": 75, "action_scale_m": 0.05,
//    "arrival_tolerance_m": 0.005, "max_arrival_wait_periods": 0}
//
// Every key but base_from_sim may be left out and takes the default below. base_from_sim
// is required: a frame calibration silently defaulted would move a real arm to the wrong
// place. Unknown keys are refused, so a misspelt limit cannot fall back to its default.

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "geometry/rigid_transform.h"
#include "robot/safety_limits.h"
#include "sim/world_layout.h"

namespace pnp::robot {

// A second of waiting at the trained 25 Hz: a longer wait is a stalled arm, not a slow one.
inline constexpr int kMaxArrivalWaitPeriods = 25;

struct GatewayConfig {
  // Maps simulation-world coordinates (policy observations and targets) into the robot's
  // base frame. Identity only as a placeholder: from_json requires it.
  geometry::RigidTransform base_from_sim;
  std::string base_frame_id = "panda_link0";  // the controller's base frame name
  SafetyLimits limits;                        // in the base frame
  // The policy was trained with these; a different period changes what an action does.
  double policy_period_s = sim::layout::kStepDuration_s;  // 0.04 s (25 Hz)
  double deadman_timeout_s = 0.1;  // no fresh action for this long: the arm holds
  // The same, rounded up to whole milliseconds: every wait the gateway bounds by it.
  std::chrono::milliseconds deadman_timeout() const {
    return std::chrono::milliseconds(static_cast<long long>(std::ceil(deadman_timeout_s * 1000)));
  }
  // The lease the gateway asks for: the controller's own dead-man, which holds the arm
  // when targets stop for this long (the protocol's default, 500 ms).
  double lease_timeout_s = 0.5;
  // Decisions of the policy per episode: the arm's 75 (sim/world_layout.h), as in the
  // arm-actuated world, which plays the gateway's episodes step for step.
  int max_episode_steps = sim::layout::kArmEpisodeSteps;
  double action_scale_m = sim::layout::kActionPositionScale;  // per axis, per step
  // Waiting for the arm. The policy was trained on a mocap hand that reaches each target
  // within one period; a real arm lags (its joints accelerate within their limits). With
  // max_arrival_wait_periods > 0, the policy is asked again only once the measured grip
  // point is within arrival_tolerance_m of the last accepted target, or after that many
  // periods of waiting, during which the target is sent again (hold). 0: ask every period.
  // Off by default: waiting (5 mm, 3 periods) lifts the block's success at the datasheet
  // accelerations but costs the cylinder's on two of three hierarchies (docs/RESULTS.md,
  // "Through the robot gateway at the Panda's datasheet accelerations").
  double arrival_tolerance_m = 0.005;
  int max_arrival_wait_periods = 0;

  // INVALID_ARGUMENT naming the key path (e.g. "limits.workspace.min_m[1]: expected a
  // number, got \"a\"") for a wrong type, an unknown or missing-but-required key, or a
  // value validate() refuses.
  static GatewayConfig from_json(const nlohmann::json& json);
  // from_json of the file's contents, each message prefixed with the path. NOT_FOUND when
  // the file cannot be read, INVALID_ARGUMENT when it is not JSON.
  static GatewayConfig load(const std::filesystem::path& path);
  nlohmann::json to_json() const;  // every key, the form from_json reads

  // INVALID_ARGUMENT naming the key: limits (SafetyLimits::validate), an empty
  // base_frame_id, non-positive periods or counts, a dead-man timeout not longer than the
  // policy period (it would trip every cycle), a lease timeout not longer than the
  // dead-man's (the lease would lapse first), or an action scale above limits.max_step_m
  // (a full action along one axis would be refused), or arrival settings outside
  // (0, 0.1] m and [0, kMaxArrivalWaitPeriods].
  void validate() const;
};

}  // namespace pnp::robot
