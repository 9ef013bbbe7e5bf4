"""A live episode on the inference service: one PredictSession stream, the choreographer's
recurrent state kept by the server between calls."""

from __future__ import annotations

import dataclasses
import queue

import grpc
import numpy as np

from pnp import names
from pnp.errors import PlatformError, ReplyError, from_rpc_error
from pnp.policy.v1 import policy_service_pb2 as policy
from pnp.sim_client import GOAL_SIZE, OBSERVATION_SIZE, vector3
from pnp.common.v1 import common_pb2 as common

_END = object()  # ends the request stream
MAX_EPISODE_STEPS = 10000  # the server's bound (sim::layout::kMaxEpisodeSteps)


@dataclasses.dataclass(frozen=True)
class Prediction:
    action: np.ndarray  # (4,): dx, dy, dz, gripper in [-1, 1]
    subtask: str | None  # "approach", "manipulate" or "retract"; None for an end-to-end policy
    value: float  # the choreographer's value estimate
    subtask_probabilities: np.ndarray
    decided: bool  # the choreographer decided anew at this step (the last subtask ended)
    step: int  # steps of this episode answered so far, this one included
    placed: bool  # the served hierarchy judges the object placed
    choreographer_checkpoint_id: int
    expert_checkpoint_id: int


class Session:
    """act(observation, goal) once per environment step, in order; close() (or a `with`
    block) ends the episode. Not for use from several threads at once."""

    def __init__(self, stub, address: str, timeout_s: float | None = None,
                 episode_steps: int = 0):
        if isinstance(episode_steps, bool) or not isinstance(episode_steps, int) \
                or not 0 <= episode_steps <= MAX_EPISODE_STEPS:
            raise ValueError(f"episode_steps: expected 0 (the served policy's own) to "
                             f"{MAX_EPISODE_STEPS}, got {episode_steps!r}")
        self._episode_steps = episode_steps
        self._address = address
        self._requests: queue.Queue = queue.Queue()
        self._responses = stub.PredictSession(iter(self._requests.get, _END), timeout=timeout_s)
        self._closed = False

    def act(self, observation, goal) -> Prediction:
        if self._closed:
            raise RuntimeError("act: the session is closed")
        request = policy.PredictSessionRequest(
            observation=common.Observation(values=_vector(observation, OBSERVATION_SIZE,
                                                          "observation")),
            goal=vector3(_vector(goal, GOAL_SIZE, "goal")),
            episode_steps=self._episode_steps)
        self._requests.put(request)
        try:
            answer = next(self._responses)
        except grpc.RpcError as e:
            self._abandon()
            raise from_rpc_error(e, "PredictSession", self._address) from None
        except StopIteration:
            self._abandon()
            raise PlatformError("PredictSession", self._address, grpc.StatusCode.UNAVAILABLE,
                                "the server ended the session") from None
        except BaseException:  # e.g. Ctrl-C while waiting: the stream is out of step now
            self._abandon()
            raise
        p = answer.prediction
        if len(p.subtask_probabilities) not in (0, 3):  # none from an end-to-end policy
            self._abandon()
            raise ReplyError(f"PredictSession reply subtask_probabilities: expected 0 or 3, got "
                             f"{len(p.subtask_probabilities)} (a newer or older platform?)")
        return Prediction(
            action=np.array([p.action.dx, p.action.dy, p.action.dz, p.action.gripper]),
            subtask=names.to_name(names.SUBTASKS, p.subtask),
            value=p.value,
            subtask_probabilities=np.array(p.subtask_probabilities),
            decided=answer.decided,
            step=answer.step,
            placed=answer.placed,
            choreographer_checkpoint_id=p.choreographer_checkpoint_id,
            expert_checkpoint_id=p.expert_checkpoint_id)

    def _abandon(self) -> None:
        """Ends the request stream and cancels the call: gRPC's thread that reads the
        requests is released, and nothing more is sent."""
        self._closed = True
        self._requests.put(_END)
        self._responses.cancel()

    def __del__(self):
        if not getattr(self, "_closed", True):
            self._abandon()

    def close(self) -> None:
        """Ends the stream (the server's status, if an error, is raised)."""
        if self._closed:
            return
        self._closed = True
        self._requests.put(_END)
        try:
            for _ in self._responses:  # none expected: the stream's end and its status
                pass
        except grpc.RpcError as e:
            if e.code() != grpc.StatusCode.CANCELLED:
                raise from_rpc_error(e, "PredictSession", self._address) from None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def _vector(values, size: int, field: str) -> np.ndarray:
    try:
        v = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{field}: expected {size} numbers, got {values!r}") from None
    if v.shape != (size,):
        raise ValueError(f"{field}: expected {size} values, got shape {v.shape}")
    return v
