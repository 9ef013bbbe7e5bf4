"""The simulation service's calls as Python methods: numpy in and out, every failure a
PlatformError carrying the service's status and message."""

from __future__ import annotations

from typing import Sequence

import grpc
import numpy as np

from pnp import names
from pnp.common.v1 import common_pb2 as common
from pnp.endpoints import Endpoints
from pnp.errors import ReplyError, from_rpc_error
from pnp.sim.v1 import sim_service_pb2 as sim
from pnp.sim.v1 import sim_service_pb2_grpc as sim_grpc

OBSERVATION_SIZE = 25
GOAL_SIZE = 3
ACTION_SIZE = 4
OBJECT_POSITION = slice(3, 6)  # docs/OBSERVATION.md: the achieved goal of the task


def checked_count(items, expected: int, what: str) -> list:
    if len(items) != expected:
        raise ReplyError(f"{what}: expected {expected}, got {len(items)} (a newer or older "
                         f"platform?)")
    return list(items)


def observation_dict(state: sim.EnvState) -> dict[str, np.ndarray]:
    checked_count(state.observation.values, OBSERVATION_SIZE, "reply observation values")
    observation = np.array(state.observation.values, dtype=np.float64)
    g = state.episode_goal
    return {
        "observation": observation,
        "achieved_goal": observation[OBJECT_POSITION].copy(),
        "desired_goal": np.array([g.x_m, g.y_m, g.z_m], dtype=np.float64),
    }


def checked_actions(actions, count: int, batched: bool) -> np.ndarray:
    """Actions of 4 values, one (batched: `count`, shape (count, 4)) as an array of shape
    (count, 4); ValueError naming the shape otherwise. Range and finiteness are the
    service's to judge (it refuses non-finite values and clips to [-1, 1], as
    FetchPickAndPlace does)."""
    expected = (count, ACTION_SIZE) if batched else (ACTION_SIZE,)
    try:
        a = np.asarray(actions, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"action: expected numbers of shape {expected}, got {actions!r}") from None
    if a.shape != expected:
        raise ValueError(f"action: expected shape {expected} (dx, dy, dz, gripper"
                         f"{' per environment' if batched else ''}), got shape {a.shape}")
    return a.reshape(count, ACTION_SIZE)


def vector3(values) -> common.Vector3:
    return common.Vector3(x_m=float(values[0]), y_m=float(values[1]), z_m=float(values[2]))


class SimClient:
    """One channel to the simulation service."""

    def __init__(self, endpoints: Endpoints, timeout_s: float = 30.0):
        self.address = endpoints.sim
        self._endpoints = endpoints
        self._channel = endpoints.channel(endpoints.sim)
        self._stub = sim_grpc.SimulationServiceStub(self._channel)
        self._timeout_s = timeout_s

    def _call(self, method: str, request):
        try:
            return getattr(self._stub, method)(request, timeout=self._timeout_s)
        except grpc.RpcError as e:
            raise from_rpc_error(e, method, self.address, self._endpoints) from None

    def create_env(self, robot: str, object: str, world: str, seed: int, count: int,
                   idle_timeout_s: float | None = None, actuation: str = "default") -> str:
        request = sim.CreateEnvRequest(
            robot=names.to_enum(names.ROBOTS, robot, "robot"),
            object=names.to_enum(names.OBJECTS, object, "object"),
            world=names.to_enum(names.WORLDS, world, "world"),
            actuation=names.to_enum(names.ACTUATIONS, actuation, "actuation"),
            seed=int(seed), count=int(count))
        if idle_timeout_s is not None:
            request.idle_timeout.FromNanoseconds(int(idle_timeout_s * 1e9))
        return self._call("CreateEnv", request).env_id

    def reset(self, env_id: str, count: int, indices: Sequence[int] = ()) -> list[sim.EnvState]:
        """The states of the environments `indices` (empty: all `count` of the batch)."""
        request = sim.ResetRequest(env_id=env_id, indices=list(indices))
        return checked_count(self._call("Reset", request).states,
                             len(indices) if indices else count, "Reset reply states")

    def step_task(self, env_id: str, actions: np.ndarray, goals: Sequence[np.ndarray],
                  indices: Sequence[int]) -> list[sim.StepResult]:
        """One step of the environments `indices`, scored on the whole task."""
        request = sim.StepRequest(env_id=env_id)
        for k, action, goal in zip(indices, actions, goals):
            request.actions.append(sim.EnvAction(
                index=int(k),
                action=common.Action(dx=action[0], dy=action[1], dz=action[2], gripper=action[3]),
                goal=vector3(goal), objective=sim.OBJECTIVE_TASK))
        return checked_count(self._call("Step", request).results, len(request.actions),
                             "Step reply results")

    def compute_reward(self, achieved, goals) -> np.ndarray:
        """The service's dense reward -||achieved - goal|| for pairs of shape (n, 3)."""
        request = sim.ComputeRewardRequest(achieved=[vector3(a) for a in achieved],
                                           goals=[vector3(g) for g in goals])
        rewards = checked_count(self._call("ComputeReward", request).rewards, len(request.goals),
                                "ComputeReward reply rewards")
        return np.array(rewards, dtype=np.float64)

    def spec(self, robot: str, object: str, world: str,
             actuation: str = "default") -> sim.GetEnvSpecResponse:
        return self._call("GetEnvSpec", sim.GetEnvSpecRequest(
            robot=names.to_enum(names.ROBOTS, robot, "robot"),
            object=names.to_enum(names.OBJECTS, object, "object"),
            world=names.to_enum(names.WORLDS, world, "world"),
            actuation=names.to_enum(names.ACTUATIONS, actuation, "actuation")))

    def close_env(self, env_id: str) -> None:
        self._call("CloseEnv", sim.CloseEnvRequest(env_id=env_id))

    def close(self) -> None:
        self._channel.close()
