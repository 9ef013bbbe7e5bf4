#include "sim/task_sampler.h"

#include "sim/world_layout.h"

namespace pnp::sim {

EpisodeLayout sample_episode_layout(Rng& rng, double object_half_height_m) {
  using namespace layout;
  const Eigen::Vector2d start = kGripperStart.head<2>();
  const double rest_z = kTableTop_z + object_half_height_m;
  EpisodeLayout out;
  Eigen::Vector2d object_xy;
  do {  // rejection sampling: accepts ~65% of draws
    object_xy = start + Eigen::Vector2d(rng.uniform(-kObjectRange, kObjectRange),
                                        rng.uniform(-kObjectRange, kObjectRange));
  } while ((object_xy - start).norm() < kObjectMinDistance);
  out.object << object_xy, rest_z;

  const Eigen::Vector2d goal_xy = start + Eigen::Vector2d(rng.uniform(-kGoalRange, kGoalRange),
                                                          rng.uniform(-kGoalRange, kGoalRange));
  double goal_z = rest_z;
  if (rng.bernoulli(kGoalAirProbability)) goal_z += rng.uniform(0.0, kGoalMaxHeight);
  out.goal << goal_xy, goal_z;
  return out;
}

}  // namespace pnp::sim
