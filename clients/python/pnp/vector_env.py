"""VectorPickAndPlaceEnv: n environments of one simulation-service batch, stepped by one
RPC per step for all n, with Gymnasium's (0.29) vector-environment API and auto-reset: when
an episode ends, the observation returned is the next episode's first, and the last one is
in info["final_observation"] (info["_final_observation"] marks which).

Seeding: environment k's episodes are the batch's (seed, k, i), i = 0, 1, ..."""

from __future__ import annotations

import numpy as np

from pnp.endpoints import Endpoints
from pnp.sim_batch import SimBatch, fault_name, goal_spaces
from pnp.sim_client import checked_actions, observation_dict
from pnp.spaces import Box, Dict

MAX_ENVS = 64  # the service's largest batch


class VectorPickAndPlaceEnv:
    metadata = {"render_modes": []}

    def __init__(self, num_envs: int, sim_address: str | Endpoints | None = None,
                 robot: str = "fetch", object: str = "block", world: str = "gym", seed: int = 0,
                 reward_type: str = "sparse", timeout_s: float = 30.0,
                 idle_timeout_s: float | None = None, actuation: str = "default"):
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or \
                not 1 <= num_envs <= MAX_ENVS:
            raise ValueError(f"num_envs: expected an integer from 1 to {MAX_ENVS}, "
                             f"got {num_envs!r}")
        self.num_envs = int(num_envs)
        self._batch = SimBatch(sim_address, robot, object, world, seed, self.num_envs,
                               reward_type, timeout_s, idle_timeout_s, actuation)
        self.robot, self.object, self.world = robot, object, world
        self.actuation = actuation
        self.reward_type = reward_type
        try:
            self.single_observation_space, self.single_action_space = goal_spaces(
                self._batch.spec)
        except BaseException:
            self._batch.close()
            raise
        self.observation_space = _batched_dict(self.single_observation_space, self.num_envs)
        self.action_space = _batched_box(self.single_action_space, self.num_envs)
        self.max_episode_steps = self._batch.spec.episode_steps
        self.success_distance_m = self._batch.spec.success_distance_m
        self._goals: np.ndarray | None = None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        states = self._batch.reset_all(seed, options, self.action_space)
        obs = _stack([observation_dict(s) for s in states])
        self._goals = obs["desired_goal"].copy()
        return obs, {"elapsed_steps": np.zeros(self.num_envs, dtype=np.int64)}

    def step(self, actions):
        if not self._batch.started() or self._goals is None:
            raise RuntimeError("step: call reset() first")
        a = checked_actions(actions, self.num_envs, batched=True)
        indices = range(self.num_envs)
        client, env_id = self._batch.client, self._batch.env_id()
        results = client.step_task(env_id, a, self._goals, indices)
        per_env = [observation_dict(r.state) for r in results]
        obs = _stack(per_env)
        rewards = self.compute_reward(obs["achieved_goal"], obs["desired_goal"], None)
        truncated = np.array([r.episode_over for r in results], dtype=bool)
        terminated = np.zeros(self.num_envs, dtype=bool)
        info = {
            "is_success": np.array([float(r.task_success) for r in results]),
            "elapsed_steps": np.array([r.state.elapsed_steps for r in results], dtype=np.int64),
            "physics_fault": np.array([fault_name(r.fault) for r in results], dtype=object),
        }
        if truncated.any():
            finished = [k for k in indices if truncated[k]]
            info["final_observation"] = np.array([None] * self.num_envs, dtype=object)
            info["_final_observation"] = truncated.copy()
            info["final_info"] = np.array([None] * self.num_envs, dtype=object)
            info["_final_info"] = truncated.copy()
            for k in finished:
                info["final_observation"][k] = per_env[k]
                info["final_info"][k] = {"is_success": info["is_success"][k],
                                         "elapsed_steps": int(info["elapsed_steps"][k]),
                                         "physics_fault": info["physics_fault"][k]}
            for k, state in zip(finished, client.reset(env_id, self.num_envs, finished)):
                fresh = observation_dict(state)
                for key in obs:
                    obs[key][k] = fresh[key]
                info["elapsed_steps"][k] = state.elapsed_steps  # the new episode's
            self._goals = obs["desired_goal"].copy()
        return obs, rewards, terminated, truncated, info

    def compute_reward(self, achieved_goal, desired_goal, info=None):
        return self._batch.compute_reward(achieved_goal, desired_goal)

    def close(self):
        self._batch.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def _stack(observations: list[dict]) -> dict[str, np.ndarray]:
    return {key: np.stack([o[key] for o in observations]) for key in observations[0]}


def _batched_box(space, n: int):
    return Box(np.tile(space.low, (n, 1)), np.tile(space.high, (n, 1)), (n,) + space.shape,
               space.dtype)


def _batched_dict(space, n: int):
    return Dict({key: _batched_box(sub, n) for key, sub in space.spaces.items()})
