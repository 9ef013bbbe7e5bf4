"""PickAndPlaceEnv: one environment of the simulation service behind the Gymnasium
goal-environment API (FetchPickAndPlace's): dict observations with `observation`,
`achieved_goal` and `desired_goal`, a sparse reward by default, `compute_reward` for
hindsight relabelling, episodes of 50 steps (75 with actuation="arm") that end truncated,
never terminated.

Seeding: the environment's episodes come from its seed, episode i of a seed being the
simulation service's episode (seed, 0, i) -- exactly the episodes `pnpctl evaluate --seed`
plays. reset(seed=s) starts over from episode 0 of seed s; reset() goes on to the next.
A physics fault (info["physics_fault"]) ends an episode early, truncated; the simulator
has then already reset the world, so that step's observation, reward and is_success are
of the new episode's first state (the diverged one is gone), and reset() goes on to the
next episode as pnpctl evaluate does."""

from __future__ import annotations

import numpy as np

from pnp.endpoints import Endpoints
from pnp.sim_batch import SimBatch, fault_name, goal_spaces
from pnp.sim_client import checked_actions, observation_dict

try:
    import gymnasium as _gymnasium
except ImportError:  # gymnasium is optional: the same API without its base class
    _gymnasium = None

ENV_ID = "pnp/PickAndPlace-v0"


class _EnvBase:
    """What gymnasium.Env provides, for when gymnasium is not installed."""

    metadata = {"render_modes": []}
    render_mode = None
    _np_random = None

    @property
    def np_random(self) -> np.random.Generator:
        """The environment's own generator (seeded by reset(seed=...)), as gymnasium's."""
        if self._np_random is None:
            self._np_random = np.random.default_rng()
        return self._np_random

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            self._np_random = np.random.default_rng(seed)

    @property
    def unwrapped(self):
        return self

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


class PickAndPlaceEnv(_gymnasium.Env if _gymnasium else _EnvBase):
    metadata = {"render_modes": []}

    def __init__(self, sim_address: str | Endpoints | None = None, robot: str = "fetch",
                 object: str = "block", world: str = "gym", seed: int = 0,
                 reward_type: str = "sparse", timeout_s: float = 30.0,
                 idle_timeout_s: float | None = None, actuation: str = "default"):
        """idle_timeout_s: how long the service keeps the environment between calls (its
        default 300 s, at most 3600 s); after that a call raises NOT_FOUND and reset()
        starts a new one. actuation: "mocap" (gym's hand), "arm" (the Panda moved by its
        controller) or "default" (the robot's own: docs/SIMULATION.md)."""
        self._batch = SimBatch(sim_address, robot, object, world, seed, 1, reward_type, timeout_s,
                               idle_timeout_s, actuation)
        self.robot, self.object, self.world = robot, object, world
        self.actuation = actuation
        self.reward_type = reward_type
        try:
            self.observation_space, self.action_space = goal_spaces(self._batch.spec)
        except BaseException:
            self._batch.close()
            raise
        self.max_episode_steps = self._batch.spec.episode_steps
        self.step_s = self._batch.spec.step_s
        self.success_distance_m = self._batch.spec.success_distance_m
        self._goal: np.ndarray | None = None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)  # seeds np_random, as gymnasium's check_env expects
        state = self._batch.reset_all(seed, options, self.action_space)[0]
        obs = observation_dict(state)
        self._goal = obs["desired_goal"]
        return obs, {"elapsed_steps": state.elapsed_steps}

    def step(self, action):
        if not self._batch.started() or self._goal is None:
            raise RuntimeError("step: call reset() first")
        a = checked_actions(action, 1, batched=False)
        result = self._batch.client.step_task(self._batch.env_id(), a, [self._goal], [0])[0]
        obs = observation_dict(result.state)
        info = {
            "is_success": float(result.task_success),
            "elapsed_steps": result.state.elapsed_steps,
            "physics_fault": fault_name(result.fault),
        }
        r = float(self.compute_reward(obs["achieved_goal"], obs["desired_goal"], info))
        return obs, r, False, bool(result.episode_over), info

    def compute_reward(self, achieved_goal, desired_goal, info=None):
        """Vectorised over any leading batch shape; `info` is unused (gymnasium's signature)."""
        return self._batch.compute_reward(achieved_goal, desired_goal)

    def close(self):
        self._batch.close()


if _gymnasium is not None and ENV_ID not in _gymnasium.registry:
    _gymnasium.register(id=ENV_ID, entry_point="pnp.env:PickAndPlaceEnv")
