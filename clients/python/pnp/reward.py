"""The task's reward and success, computed locally (vectorised), so HER relabelling needs no
round-trip. The dense reward equals the simulation service's ComputeReward; the sparse one
is FetchPickAndPlace's: 0 when the object is within the success distance of the goal,
-1 otherwise (0 exactly when info["is_success"] is 1)."""

from __future__ import annotations

import numpy as np

REWARD_TYPES = ("sparse", "dense")


def goal_distance(achieved_goal, desired_goal) -> np.ndarray:
    """Euclidean distance over the last axis; any leading batch shape."""
    a = np.asarray(achieved_goal, dtype=np.float64)
    d = np.asarray(desired_goal, dtype=np.float64)
    if a.shape != d.shape or a.shape[-1:] != (3,):
        raise ValueError(f"achieved_goal and desired_goal: expected the same shape ending in 3, "
                         f"got {a.shape} and {d.shape}")
    return np.linalg.norm(a - d, axis=-1)


def compute_reward(achieved_goal, desired_goal, reward_type: str,
                   success_distance_m: float) -> np.ndarray:
    distance = goal_distance(achieved_goal, desired_goal)
    if reward_type == "dense":
        return -distance
    if reward_type == "sparse":
        return np.where(distance >= success_distance_m, -1.0, 0.0)
    raise ValueError(f"reward_type: expected one of {', '.join(REWARD_TYPES)}, got {reward_type!r}")


def is_success(achieved_goal, desired_goal, success_distance_m: float) -> np.ndarray:
    """As the simulator judges it: the object strictly within the success distance."""
    return goal_distance(achieved_goal, desired_goal) < success_distance_m
