#pragma once
// Gravity compensation for the arm, as a real arm's controller provides it: the joint
// torques that hold the arm's own weight, -J_com^T (M g), where J_com is the Jacobian of
// the arm subtree's centre of mass and M its mass. Without it the soft mocap weld lets
// the arm sag by centimetres. Written into qfrc_applied once per policy step (the
// posture changes little in 40 ms); costs one subtree Jacobian, no allocation.

#include <mujoco/mujoco.h>

#include <vector>

namespace pnp::sim {

class GravityCompensation {
 public:
  GravityCompensation(const mjModel* m, int arm_root_body);

  // Needs d->subtree_com and d->cdof current (any mj_step or mj_forward leaves them so).
  void apply(const mjModel* m, mjData* d);

 private:
  int root_body_;
  mjtNum subtree_mass_;
  std::vector<mjtNum> jacobian_;  // 3 x nv
};

}  // namespace pnp::sim
