#pragma once
// Where each episode puts the object and the goal, by the world's parameters: object xy
// within +-0.15 m of the gripper's start xy and at least 0.10 m from it, resting on the
// table; goal xy within +-0.15 m, on the table or, with probability 0.5, raised by up to
// 0.15 m (paper) or 0.45 m (gym).

#include <Eigen/Core>

#include "common/rng.h"
#include "sim/world_profile.h"

namespace pnp::sim {

struct EpisodeLayout {
  Eigen::Vector3d object;  // object centre at rest
  Eigen::Vector3d goal;    // where the object centre must go
};

EpisodeLayout sample_episode_layout(Rng& rng, double object_half_height_m,
                                    const WorldParameters& world);

}  // namespace pnp::sim
