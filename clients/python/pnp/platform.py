"""Platform: the training services, the store behind them and the inference service, from
Python -- what pnpctl does from a shell."""

from __future__ import annotations

import secrets

import grpc

from pnp import names, records
from pnp.endpoints import Endpoints
from pnp.errors import PlatformError, from_rpc_error
from pnp.policy.v1 import policy_service_pb2 as policy
from pnp.policy.v1 import policy_service_pb2_grpc as policy_grpc
from pnp.session import Session
from pnp.train.v1 import train_service_pb2 as train
from pnp.train.v1 import train_service_pb2_grpc as train_grpc

_DEFAULT_ALGORITHM = {"approach": "ddpg_her", "manipulate": "ddpg_her", "retract": "ddpg_her",
                      "hlc": "a3c", "e2e": "ddpg_her"}
# Any training service answers for every run of the store it serves; with one shared store
# (scripts/run, deploy/) this one answers questions that name no role.
_STORE_READER = "approach"


class Run:
    """A training run on its role's training service."""

    def __init__(self, platform: "Platform", role: str, run_id: int):
        self.platform = platform
        self.role = role
        self.run_id = run_id

    def info(self) -> dict:
        return records.run_record(self.platform._train_call(
            self.role, "GetTrainingRun", train.GetTrainingRunRequest(run_id=self.run_id)).run)

    def watch(self):
        """Yields {"run": ..., "metric": ... or None} as the run progresses: its state now,
        then each new evaluation, then its final state; ends when the run has finished."""
        stub, address = self.platform._training(self.role)
        try:
            for message in stub.WatchTrainingRun(train.WatchTrainingRunRequest(run_id=self.run_id)):
                if message.heartbeat:  # nothing happened; the server shows it is alive
                    continue
                yield {"run": records.run_record(message.run),
                       "metric": records.metric_record(message.metric)
                       if message.HasField("metric") else None}
        except grpc.RpcError as e:
            raise from_rpc_error(e, "WatchTrainingRun", address,
                                 self.platform.endpoints) from None

    def wait(self) -> dict:
        """Blocks until the run has finished; returns its final record (state "succeeded",
        "failed" or "cancelled"; a failed run's reason is in "error")."""
        last = None
        for progress in self.watch():
            last = progress["run"]
        return last if last is not None else self.info()

    def metrics(self):
        return self.platform.metrics(self.run_id, role=self.role)

    def checkpoints(self) -> list[dict]:
        return self.platform.checkpoints(self.run_id, role=self.role)

    def cancel(self) -> dict:
        return records.run_record(self.platform._train_call(
            self.role, "CancelTrainingRun", train.CancelTrainingRunRequest(run_id=self.run_id)).run)

    def __repr__(self):
        return f"Run({self.role}, {self.run_id})"


class Platform:
    def __init__(self, endpoints: Endpoints | dict | None = None, timeout_s: float = 30.0):
        """`endpoints`: Endpoints, a dict of addresses by service name (sim, approach, ...,
        inference), or None: Endpoints.discover() (scripts/run's addresses or pnpctl's
        environment variables)."""
        if endpoints is None:
            endpoints = Endpoints.discover()
        elif isinstance(endpoints, dict):
            endpoints = Endpoints.from_mapping(endpoints)
        elif not isinstance(endpoints, Endpoints):
            raise ValueError(f"endpoints: expected Endpoints, a dict or None, got {endpoints!r}")
        self.endpoints = endpoints
        self.timeout_s = timeout_s
        self._channels: dict[str, grpc.Channel] = {}

    def _channel(self, address: str) -> grpc.Channel:
        if address not in self._channels:
            self._channels[address] = self.endpoints.channel(address)
        return self._channels[address]

    def _training(self, role: str):
        address = self.endpoints.training(role)
        return train_grpc.TrainingServiceStub(self._channel(address)), address

    def _train_call(self, role: str, method: str, request):
        stub, address = self._training(role)
        try:
            return getattr(stub, method)(request, timeout=self.timeout_s)
        except grpc.RpcError as e:
            raise from_rpc_error(e, method, address, self.endpoints) from None

    def _policy_call(self, method: str, request):
        stub = policy_grpc.PolicyServiceStub(self._channel(self.endpoints.inference))
        try:
            return getattr(stub, method)(request, timeout=self.timeout_s)
        except grpc.RpcError as e:
            raise from_rpc_error(e, method, self.endpoints.inference,
                                 self.endpoints) from None

    def train(self, role: str, robot: str = "fetch", object: str = "block", world: str = "gym",
              seed: int = 0, actuation: str = "default", preset: str | None = None, algorithm: str | None = None,
              max_steps: int | None = None, target_success: float | None = None,
              eval_interval_steps: int | None = None, eval_episodes: int | None = None,
              parent_checkpoint_id: int | None = None, prefix_checkpoint_ids=(),
              expert_checkpoint_ids=(), ddpg: dict | None = None, a3c: dict | None = None) -> Run:
        """Starts a run on the role's training service (the preset's configuration, default
        the platform's default preset, with the given fields replaced)."""
        names.to_enum(names.ROLES, role, "role")
        algorithm = algorithm or _DEFAULT_ALGORITHM[role]
        stop = train.StopRule()
        for field, value in (("max_steps", max_steps), ("target_success", target_success),
                             ("eval_interval_steps", eval_interval_steps),
                             ("eval_episodes", eval_episodes)):
            if value is not None:
                setattr(stop, field, value)
        request = train.CreateTrainingRunRequest(
            role=names.to_enum(names.ROLES, role, "role"),
            algorithm=names.to_enum(names.ALGORITHMS, algorithm, "algorithm"),
            robot=names.to_enum(names.ROBOTS, robot, "robot"),
            object=names.to_enum(names.OBJECTS, object, "object"),
            world=names.to_enum(names.WORLDS, world, "world"),
            actuation=names.to_enum(names.ACTUATIONS, actuation, "actuation"),
            seed=seed, stop=stop, preset=preset or "",
            parent_checkpoint_id=parent_checkpoint_id or 0,
            prefix_checkpoint_ids=list(prefix_checkpoint_ids),
            expert_checkpoint_ids=list(expert_checkpoint_ids),
            ddpg=_config(train.DdpgHerConfig, ddpg, "ddpg"),
            a3c=_config(train.A3cConfig, a3c, "a3c"),
            # One key per run meant: a call retried after its answer was lost returns that run.
            request_id=secrets.token_hex(16))
        run = self._train_call(role, "CreateTrainingRun", request).run
        return Run(self, role, run.run_id)

    def run(self, run_id: int, role: str | None = None) -> Run:
        """An existing run (its role is looked up when not given)."""
        if role is None:
            run = self._train_call(_STORE_READER, "GetTrainingRun",
                                   train.GetTrainingRunRequest(run_id=run_id)).run
            role = records.run_record(run)["role"]
        return Run(self, role, run_id)

    def runs(self, state: str | None = None, role: str | None = None) -> list[dict]:
        """Every run, newest first: of every role (each from its own training service;
        one that is down is skipped unless all are), or of `role`; optionally those in
        `state`."""
        request_state = names.to_enum(names.RUN_STATES, state, "state") if state else 0
        if role is not None:
            names.to_enum(names.ROLES, role, "role")
            return self._role_runs(role, request_state)
        out, down = [], []
        for each in names.ROLES:
            try:
                out.extend(self._role_runs(each, request_state))
            except PlatformError as e:
                if e.code != grpc.StatusCode.UNAVAILABLE:
                    raise
                down.append(e)
        if len(down) == len(names.ROLES):
            raise down[0]
        return sorted(out, key=lambda run: run["run_id"], reverse=True)

    def _role_runs(self, role: str, request_state: int) -> list[dict]:
        """One role's runs from its training service, every page."""
        out, token = [], ""
        while True:
            page = self._train_call(role, "ListTrainingRuns", train.ListTrainingRunsRequest(
                page_size=1000, page_token=token, state=request_state))
            out.extend(records.run_record(r) for r in page.runs)
            token = page.next_page_token
            if not token:
                return out

    def metrics(self, run_id: int, role: str = _STORE_READER):
        """A run's evaluations: a pandas DataFrame when pandas is importable, else a list
        of dicts (env_steps, wall_s, task_success, subtask_success, ...)."""
        points = self._train_call(role, "GetRunMetrics", train.GetRunMetricsRequest(run_id=run_id))
        return records.as_table([records.metric_record(p) for p in points.points])

    def checkpoints(self, run_id: int | None = None, role: str = _STORE_READER) -> list[dict]:
        """A run's checkpoints, or every run's when `run_id` is None."""
        ids = [run_id] if run_id is not None else [r["run_id"] for r in self.runs()]
        out = []
        for i in ids:
            response = self._train_call(role, "ListCheckpoints",
                                        train.ListCheckpointsRequest(run_id=i))
            out.extend(records.checkpoint_record(c) for c in response.checkpoints)
        return out

    def promote(self, *checkpoint_ids: int) -> list[dict]:
        """Serves these checkpoints (one role each; a hierarchy's four together, atomically)."""
        if not checkpoint_ids:
            raise ValueError("checkpoint_ids: expected at least one checkpoint id")
        response = self._policy_call("PromoteCheckpoint", policy.PromoteCheckpointRequest(
            checkpoint_ids=[int(i) for i in checkpoint_ids]))
        return [records.promoted_record(p) for p in response.promoted]

    def serving_status(self) -> dict:
        response = self._policy_call("GetServingStatus", policy.GetServingStatusRequest())
        return {"ready": response.ready,
                "roles": [records.served_role_record(r) for r in response.roles]}

    def session(self, episode_steps: int = 0) -> Session:
        """A live episode on the inference service (see Session). episode_steps: how long
        the episode lasts (an environment's max_episode_steps), to which the hierarchy's
        subtask step caps scale; 0: the served policy's own (50 on the mocap hand, 75 on
        the arm)."""
        stub = policy_grpc.PolicyServiceStub(self._channel(self.endpoints.inference))
        return Session(stub, self.endpoints.inference, episode_steps=episode_steps)

    def close(self) -> None:
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def _config(message_type, values: dict | None, field: str):
    message = message_type()
    for key, value in (values or {}).items():
        if key not in message_type.DESCRIPTOR.fields_by_name:
            raise ValueError(f"{field}.{key}: not a setting; expected one of "
                             f"{', '.join(message_type.DESCRIPTOR.fields_by_name)}")
        if isinstance(value, (list, tuple)):
            getattr(message, key).extend(value)
        else:
            setattr(message, key, value)
    return message
