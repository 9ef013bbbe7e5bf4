#include "sim/task_sampler.h"

#include "sim/world_layout.h"

namespace pnp::sim {

EpisodeLayout sample_episode_layout(Rng& rng, double object_half_height_m,
                                    const WorldParameters& world) {
  const Eigen::Vector2d start = world.gripper_start().head<2>();
  const double rest_z = layout::kTableTop_z + object_half_height_m;
  EpisodeLayout out;
  Eigen::Vector2d object_xy;
  const double r = world.object_range_m;
  do {  // rejection sampling: accepts ~65% of draws
    object_xy = start + Eigen::Vector2d(rng.uniform(-r, r), rng.uniform(-r, r));
  } while ((object_xy - start).norm() < world.object_min_distance_m);
  out.object << object_xy, rest_z;

  const double g = world.goal_range_m;
  const Eigen::Vector2d goal_xy = start + Eigen::Vector2d(rng.uniform(-g, g), rng.uniform(-g, g));
  double goal_z = rest_z;
  if (rng.bernoulli(world.goal_air_probability))
    goal_z += rng.uniform(0.0, world.goal_max_height_m);
  out.goal << goal_xy, goal_z;
  return out;
}

}  // namespace pnp::sim
