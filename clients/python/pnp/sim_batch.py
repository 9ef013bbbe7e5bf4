"""SimBatch: what the single and the vector environment share -- a batch of simulation-
service environments of one world, created lazily from a seed, re-created when reseeded,
released on close; and the task's spaces, reward and faults."""

from __future__ import annotations

import grpc
import numpy as np

from pnp import names, reward
from pnp.endpoints import Endpoints
from pnp.errors import PlatformError
from pnp.sim.v1 import sim_service_pb2 as sim
from pnp.sim_client import ACTION_SIZE, GOAL_SIZE, OBSERVATION_SIZE, SimClient
from pnp.spaces import Box, Dict


def resolve_endpoints(sim_address: str | Endpoints | None) -> Endpoints:
    """An address (with pnpctl's TLS environment variables), full Endpoints, or None: the
    address pnpctl would use (PNP_SIM_ADDRESS or runs/platform/endpoints.json)."""
    if isinstance(sim_address, Endpoints):
        return sim_address
    if sim_address is None:
        return Endpoints.discover()
    if not isinstance(sim_address, str) or not sim_address:
        raise ValueError(f"sim_address: expected \"host:port\" or Endpoints, got {sim_address!r}")
    return Endpoints.from_env(Endpoints(sim=sim_address))


def check_seed(seed, field: str) -> None:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise ValueError(f"{field}: expected an integer in [0, 2^64), got {seed!r}")


def fault_name(fault: int) -> str | None:
    """Why the simulator reset an environment mid-episode ("unstable", ...); None if not."""
    if fault in (sim.PHYSICS_FAULT_UNSPECIFIED, sim.PHYSICS_FAULT_NONE):
        return None
    return sim.PhysicsFault.Name(fault).removeprefix("PHYSICS_FAULT_").lower()


def goal_spaces(spec) -> tuple:
    """(observation_space, action_space) from the service's GetEnvSpec."""
    obs, goal, act = spec.observation, spec.goal, spec.action
    if (obs.size, goal.size, act.size) != (OBSERVATION_SIZE, GOAL_SIZE, ACTION_SIZE):
        raise RuntimeError(f"the simulation service's spec has sizes {obs.size}, {goal.size}, "
                           f"{act.size}; this package expects {OBSERVATION_SIZE}, {GOAL_SIZE}, "
                           f"{ACTION_SIZE} (a newer or older platform?)")
    observation_space = Dict({
        "observation": Box(np.array(obs.low), np.array(obs.high), (obs.size,), np.float64),
        "achieved_goal": Box(np.array(goal.low), np.array(goal.high), (goal.size,), np.float64),
        "desired_goal": Box(np.array(goal.low), np.array(goal.high), (goal.size,), np.float64),
    })
    # float32 as FetchPickAndPlace's action space; the service takes doubles.
    action_space = Box(np.array(act.low, dtype=np.float32), np.array(act.high, dtype=np.float32),
                       (act.size,), np.float32)
    return observation_space, action_space


class SimBatch:
    def __init__(self, sim_address: str | Endpoints | None, robot: str, object: str, world: str,
                 seed: int, count: int, reward_type: str, timeout_s: float,
                 idle_timeout_s: float | None = None, actuation: str = "default"):
        names.to_enum(names.ROBOTS, robot, "robot")
        names.to_enum(names.OBJECTS, object, "object")
        names.to_enum(names.WORLDS, world, "world")
        names.to_enum(names.ACTUATIONS, actuation, "actuation")
        self.actuation = actuation
        if reward_type not in reward.REWARD_TYPES:
            raise ValueError(f"reward_type: expected one of {', '.join(reward.REWARD_TYPES)}, "
                             f"got {reward_type!r}")
        check_seed(seed, "seed")
        self.robot, self.object, self.world = robot, object, world
        self.count = count
        self.reward_type = reward_type
        self.seed = int(seed)
        self.idle_timeout_s = idle_timeout_s
        self.client = SimClient(resolve_endpoints(sim_address), timeout_s)
        try:
            self.spec = self.client.spec(robot, object, world, actuation)
        except BaseException:
            self.client.close()
            raise
        self._env_id: str | None = None
        self._closed = False

    def env_id(self, reseed: int | None = None) -> str:
        """The batch's id, created from the seed at first use; `reseed`: a new batch whose
        episodes are those of that seed, from its first."""
        if self._closed:
            raise RuntimeError("reset: the environment is closed")
        if reseed is not None:
            check_seed(reseed, "seed")
            self.seed = int(reseed)
            self.release()
        if self._env_id is None:
            self._env_id = self.client.create_env(self.robot, self.object, self.world, self.seed,
                                                  self.count, self.idle_timeout_s, self.actuation)
        return self._env_id

    def reset_all(self, seed: int | None, options: dict | None, action_space) -> list:
        """Gymnasium's reset: new episodes in every environment (from the first of `seed`'s
        when given, which also seeds the action space's sampler); their states."""
        if options:
            raise ValueError(f"options: expected none, got {sorted(options)}")
        env_id = self.env_id(reseed=seed)
        if seed is not None:
            action_space.seed(int(seed))
        try:
            return self.client.reset(env_id, self.count)
        except PlatformError as e:
            if e.code != grpc.StatusCode.NOT_FOUND:
                raise
            # Expired on the service (idle longer than its idle timeout): a new batch,
            # whose episodes start again from the seed's first.
            self._env_id = None
            return self.client.reset(self.env_id(), self.count)

    def started(self) -> bool:
        return self._env_id is not None

    def compute_reward(self, achieved_goal, desired_goal):
        return reward.compute_reward(achieved_goal, desired_goal, self.reward_type,
                                     self.spec.success_distance_m)

    def release(self) -> None:
        if self._env_id is not None:
            env_id, self._env_id = self._env_id, None
            try:
                self.client.close_env(env_id)
            except PlatformError as e:
                if e.code != grpc.StatusCode.NOT_FOUND:  # expired already: nothing to release
                    raise

    def close(self) -> None:
        if self._closed:
            return
        try:
            self.release()
        finally:
            self._closed = True
            self.client.close()
